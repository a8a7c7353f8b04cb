#!/usr/bin/env bash
# Installs what the firmware's build needs beyond the Rust toolchain and its thumbv7em target, when
# it is missing (idempotent: nothing to do when present). test.sh and ../test-all.sh run it.
#
#   flip-link  the linker of the thumbv7em images (.cargo/config.toml): the stack at the bottom of
#              RAM, below the statics, so that an overflow faults instead of overwriting them.
#              `cargo install`, pinned, about 10 s.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")"

FLIP_LINK_VERSION=0.1.12

if ! command -v flip-link >/dev/null; then
    echo "installing flip-link $FLIP_LINK_VERSION (cargo install)"
    # A host tool: this directory's cargo configuration builds for thumbv7em by default.
    cargo install flip-link --locked --version "$FLIP_LINK_VERSION" \
        --target "$(rustc -vV | sed -n 's/^host: //p')"
fi
if ! command -v flip-link >/dev/null; then
    echo "install-tools.sh: flip-link is installed in cargo's bin directory" \
        "(${CARGO_HOME:-$HOME/.cargo}/bin), which is not on PATH" >&2
    exit 1
fi
