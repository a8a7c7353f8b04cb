#!/usr/bin/env bash
# Runs a firmware image on QEMU's STM32F405 board (netduinoplus2) with semihosting, counting
# instructions deterministically (-icount shift=3: 8 ns of virtual time per instruction; sleep=off
# so that semihosting output does not advance the virtual clock). Exit status: the image's own
# (0 pass, 1 fail), 124 if it hung past the timeout, 2 if the image or QEMU is missing.
#
#   ./qemu.sh target/thumbv7em-none-eabihf/release/selftest
#   CARGO_TARGET_THUMBV7EM_NONE_EABIHF_RUNNER="$PWD/qemu.sh" cargo run --release --bin selftest
#
# QEMU_TIMEOUT_S (default 120) bounds the run. QEMU_SERIAL=<file> captures the first serial port
# (USART1: the e2e image's live link) into that file; without it the port is not connected.
set -euo pipefail

elf="${1:?usage: qemu.sh <elf>}"
if [[ ! -f "$elf" ]]; then
    echo "qemu.sh: no image at $elf" >&2
    exit 2
fi
if ! command -v qemu-system-arm >/dev/null; then
    echo "qemu.sh: qemu-system-arm is not installed (apt-get install -y qemu-system-arm)" >&2
    exit 2
fi
serial=none
if [[ -n "${QEMU_SERIAL:-}" ]]; then
    serial="file:$QEMU_SERIAL"
fi
exec timeout "${QEMU_TIMEOUT_S:-120}" qemu-system-arm \
    -machine netduinoplus2 -cpu cortex-m4 \
    -nographic -monitor none -serial "$serial" \
    -semihosting-config enable=on,target=native \
    -icount shift=3,sleep=off \
    -kernel "$elf"
