#!/usr/bin/env bash
# Every test of the project, with the set-up a fresh machine needs (idempotent, quick when present):
# the thumbv7em target, flip-link (the firmware's linker, `cargo install`), Debian's qemu-system-arm
# for the emulated MCU, a TrueType font for plots, and numpy and scipy for the independent generator
# of the golden reference.
set -euo pipefail
cd "$(dirname "$0")"

as_root() {
    if [ "$(id -u)" -eq 0 ]; then "$@"; elif command -v sudo >/dev/null; then sudo "$@"; else
        echo "need root to run: $*" >&2; return 1; fi
}

apt_install() {
    # apt-get update only when a package is missing.
    local missing=()
    for pkg in "$@"; do dpkg -s "$pkg" >/dev/null 2>&1 || missing+=("$pkg"); done
    if [ "${#missing[@]}" -gt 0 ]; then
        echo "installing ${missing[*]}"
        as_root apt-get update -qq
        as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
    fi
}

python_packages() {
    # pip only when numpy or scipy is missing; the versions the generator was checked with.
    python3 -c 'import numpy, scipy' 2>/dev/null && return 0
    local pip=(python3 -m pip install --quiet --disable-pip-version-check -r tests/golden/requirements.txt)
    "${pip[@]}" || "${pip[@]}" --break-system-packages
}

echo "== set-up"
rustup target add thumbv7em-none-eabihf
firmware/install-tools.sh
apt_install qemu-system-arm binutils fonts-dejavu-core
python_packages

echo "== the golden 3D reference, re-derived by its independent generator (Python, scipy)"
python3 tests/golden/bench_3d_cables.py --check

echo "== host tests (model-core in f64 and f32, host-sim, cross-crate)"
cargo test --workspace

echo "== model-core and the live link's record format build without std for the MCU"
cargo build -p model-core -p robot-link --target thumbv7em-none-eabihf

echo "== firmware (host tests of its library, QEMU images, size budget)"
firmware/test.sh

echo "== all tests passed"
