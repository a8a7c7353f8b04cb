#!/usr/bin/env bash
# Prints the path of the host-sim binary the workspace's tests run, building it as
# `cargo test --workspace` does (its command-line tests need it): the scripts that run host-sim
# after the tests (firmware/test.sh, report/study.sh --quick) reuse that build rather than build
# every dependency again in release. Its profile is cargo's `test` (optimised, debug assertions on).
set -euo pipefail
cd "$(dirname "$0")/.."
messages=$(cargo test --workspace --no-run --message-format=json)
# The binary itself (its unit tests are a bin target too, built with "test":true).
path=$(grep '"target":{"kind":\["bin"\],"crate_types":\["bin"\],"name":"host-sim"' <<<"$messages" |
    grep '"test":false}' | grep -o '"executable":"[^"]*"' | head -n 1 | cut -d '"' -f 4)
if [[ -z "$path" || ! -x "$path" ]]; then
    echo "host-sim/tested.sh: cargo test --workspace --no-run named no host-sim binary" >&2
    exit 1
fi
echo "$path"
