#!/usr/bin/env bash
# Every firmware check, from any working directory:
#   formatting, host tests of the library (the fault scenarios listed apart), clippy -D warnings
#   (host tests and target build), the QEMU images (selftest, golden, e2e with its live link checked
#   by host-sim against the f64 reference, the RTIC estimator image
#   and its sampling through a cold estimate, bench, the fault and panic images that must exit
#   with failure rather than hang, and the overflow image, whose stack overflow must end in a
#   reported HardFault with the statics intact), the board image (build only: it needs the real
#   STM32F405's clock tree), the tendon image (golden tendon rows and a recorded actuation), and the
#   estimator and tendon images' flash/RAM budgets against the committed expected values in
#   expected/; then the robot file: robots that do not fit must not build, and the `robot` image of
#   the default robot and of robots/two_section.toml, checked by host-sim against the same files.
#
# Installs flip-link, the images' linker, when it is missing (install-tools.sh: `cargo install`,
# pinned). Needs the thumbv7em-none-eabihf target, qemu-system-arm and readelf (binutils); it
# installs none of these and says what is missing. Environment:
# The live link's and the robots' checks run host-sim as the root workspace's tests build it
# (host-sim/tested.sh: after `cargo test --workspace`, nothing more to build).
#   UPDATE_EXPECTED=1     rewrite expected/*.size and expected/bench.run from this run
#   FIRMWARE_BUDGET=report  report an over-budget estimator image without failing
#   QEMU_TIMEOUT_S=120    bound on each QEMU run
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")"

TARGET=thumbv7em-none-eabihf
RELEASE="target/$TARGET/release"
OUT="target/test-out"
FLASH_BUDGET_B=65536
RAM_BUDGET_B=16384
# The tendon image's budget: an STM32G4-class motor-control MCU (128 KiB flash, 32 KiB RAM).
TENDON_FLASH_BUDGET_B=131072
TENDON_RAM_BUDGET_B=32768

missing=()
if command -v cargo >/dev/null; then
    ./install-tools.sh || missing+=("flip-link (./install-tools.sh failed)")
else
    missing+=("cargo (the Rust toolchain pinned by ../rust-toolchain.toml)")
fi
if command -v rustc >/dev/null && [[ ! -d "$(rustc --print sysroot)/lib/rustlib/$TARGET" ]]; then
    missing+=("the Rust target $TARGET (rustup target add $TARGET)")
fi
cargo fmt --version >/dev/null 2>&1 || missing+=("rustfmt (rustup component add rustfmt)")
cargo clippy --version >/dev/null 2>&1 || missing+=("clippy (rustup component add clippy)")
command -v qemu-system-arm >/dev/null || missing+=("qemu-system-arm (apt-get install -y qemu-system-arm)")
command -v readelf >/dev/null || missing+=("readelf (apt-get install -y binutils)")
if ((${#missing[@]})); then
    printf 'firmware/test.sh: missing: %s\n' "${missing[@]}" >&2
    exit 1
fi

HOST="$(rustc -vV | sed -n 's/^host: //p')"
mkdir -p "$OUT"
passed=0
failed=0
failures=()
summary=()

# check NAME COMMAND...: runs a check, times it, tallies it; never stops the script.
check() {
    local name="$1"
    shift
    local start=$SECONDS
    printf '\n== %s\n' "$name"
    if "$@"; then
        passed=$((passed + 1))
        summary+=("pass  $(printf '%4d' $((SECONDS - start))) s  $name")
    else
        failed=$((failed + 1))
        failures+=("$name")
        summary+=("FAIL  $(printf '%4d' $((SECONDS - start))) s  $name")
    fi
}

# run_image NAME EXPECTED_STATUS PATTERN: runs an image on QEMU; passes when it exits with
# EXPECTED_STATUS and its output has a line matching PATTERN.
run_image() {
    local name="$1" want="$2" pattern="$3" status=0
    ./qemu.sh "$RELEASE/$name" >"$OUT/$name.out" 2>&1 || status=$?
    grep -v '^bench case=' "$OUT/$name.out" | tail -n 12
    if [[ "$status" != "$want" ]]; then
        echo "$name: exit status $status, expected $want (124: hung until the timeout)"
        return 1
    fi
    if ! grep -Eq "$pattern" "$OUT/$name.out"; then
        echo "$name: no line matching /$pattern/"
        return 1
    fi
}

# compare_expected FILE ACTUAL_FILE: the committed expected values must match this run: every
# field exactly except the numbers themselves, each within 0.5 %. QEMU with -icount and a pinned
# toolchain count the same binary's instructions identically, but the binary depends a little on
# where the checkout lies: this workspace builds model-core from outside its root, so model-core's
# symbol hashes carry its path, and the machine outliner's choices follow them (a clone elsewhere
# measured up to 0.11 % more or fewer instructions, and 8 B of code). UPDATE_EXPECTED=1 rewrites them.
compare_expected() {
    local expected="$1" actual="$2"
    if [[ "${UPDATE_EXPECTED:-0}" == 1 ]]; then
        cp "$actual" "$expected"
        echo "rewrote $expected"
        return 0
    fi
    if [[ ! -f "$expected" ]]; then
        echo "$expected is missing: run with UPDATE_EXPECTED=1 and commit it"
        return 1
    fi
    if ! paste -d '\n' "$expected" "$actual" | awk '
        # Numbers within 0.5 % of each other; everything else equal.
        function near(a, b) { return a == b || (a + 0 > 0 && (a - b < 0 ? b - a : a - b) <= 0.005 * a) }
        NR % 2 == 1 { want = $0; next }
        {
            n = split(want, w, /[ =]/); m = split($0, g, /[ =]/)
            if (n != m) { bad = 1; print "- " want; print "+ " $0; next }
            for (i = 1; i <= n; i++) {
                if (w[i] == g[i]) continue
                if (w[i] ~ /^[0-9]+$/ && g[i] ~ /^[0-9]+$/ && near(w[i], g[i])) continue
                bad = 1; print "- " want; print "+ " $0; break
            }
        }
        END { exit bad }' || [[ "$(wc -l <"$expected")" != "$(wc -l <"$actual")" ]]; then
        diff -u "$expected" "$actual"
        echo "$expected differs from this run beyond 0.5 % (UPDATE_EXPECTED=1 rewrites it; review the change)"
        return 1
    fi
    if ! diff -q "$expected" "$actual" >/dev/null; then
        echo "$expected: this run within 0.5 % of it (the checkout's path moves the counts a little)"
    fi
}

# elf_sizes ELF [SKIP]: "flash static_ram" in bytes from the program headers: flash is the span of
# the loaded segments at flash addresses from the start of flash, static RAM every segment's memory
# size in RAM. Segments loaded at an address in SKIP (" 0x0801ace0 ...") are left out.
elf_sizes() {
    local flash=0 ram=0 skip="${2:-}" type off vaddr paddr filesz memsz rest
    while read -r type off vaddr paddr filesz memsz rest; do
        [[ "$type" == LOAD ]] || continue
        [[ "$skip" == *" $(printf '0x%08x' "$paddr") "* ]] && continue
        # Flash is the span the image occupies from the start of flash, alignment gaps between
        # sections included (as the image's own linker symbols count it).
        if ((paddr >= 0x08000000 && paddr < 0x08100000 && paddr + filesz - 0x08000000 > flash)); then
            flash=$((paddr + filesz - 0x08000000))
        fi
        if ((vaddr >= 0x20000000 && vaddr < 0x20020000)); then ram=$((ram + memsz)); fi
    done < <(readelf -lW "$1")
    echo "$flash $ram"
}

# flash_without_defmt ELF: the flash span of the loaded segments but the one of defmt's markers
# (`.defmt*`), which an image without defmt's linker script (no defmt logger) keeps in flash after
# everything its own linker symbols delimit (2 B, and the alignment before them).
flash_without_defmt() {
    local markers flash ram
    markers=" $(readelf -SW "$1" | awk '{
        for (i = 1; i <= NF; i++) if ($i ~ /^\.defmt/) printf "0x%s ", $(i + 2)
    }')"
    read -r flash ram < <(elf_sizes "$1" "$markers")
    echo "$flash"
}

# image_budget IMAGE FLASH_BUDGET RAM_BUDGET: the image's flash and RAM (static + the stack's
# high-water mark it reported) within budget and equal to expected/IMAGE.size.
image_budget() {
    local image="$1" flash_budget="$2" ram_budget="$3"
    local elf="$RELEASE/$image" line flash static_ram stack reported_flash reported_static
    read -r flash static_ram < <(elf_sizes "$elf")
    line="$(grep -E '^memory: ' "$OUT/$image.out" || true)"
    if [[ -z "$line" ]]; then
        echo "the $image image reported no memory line"
        return 1
    fi
    # memory: flash F B, static RAM S B, stack high-water K B, RAM total T B
    read -r reported_flash reported_static stack < <(sed -E \
        's/^memory: flash ([0-9]+) B, static RAM ([0-9]+) B, stack high-water ([0-9]+) B.*/\1 \2 \3/' <<<"$line")
    local own
    own="$(flash_without_defmt "$elf")"
    if [[ "$reported_flash" != "$own" || "$reported_static" != "$static_ram" ]]; then
        echo "readelf ($own B flash without defmt's markers, $static_ram B RAM) and the image's" \
            "linker symbols ($reported_flash, $reported_static) disagree"
        return 1
    fi
    local ram=$((static_ram + stack))
    {
        echo "# $image image, bytes (firmware/test.sh; budget $flash_budget flash, $ram_budget RAM)"
        echo "flash $flash"
        echo "static_ram $static_ram"
        echo "stack_high_water $stack"
        echo "ram_total $ram"
    } >"$OUT/$image.size"
    cat "$OUT/$image.size"
    local ok=0
    compare_expected "expected/$image.size" "$OUT/$image.size" || ok=1
    if ((flash > flash_budget || ram > ram_budget)); then
        echo "OVER BUDGET: flash $flash of $flash_budget B, RAM $ram of $ram_budget B" \
            "(static $static_ram + stack $stack)"
        [[ "${FIRMWARE_BUDGET:-enforce}" == report ]] || ok=1
    fi
    return "$ok"
}

budget() {
    local ok=0
    image_budget estimator "$FLASH_BUDGET_B" "$RAM_BUDGET_B" || ok=1
    echo "all images (flash B, static RAM B):"
    local image
    for image in selftest golden e2e estimator bench tendon; do
        [[ -f "$RELEASE/$image" ]] && printf '  %-10s %s\n' "$image" "$(elf_sizes "$RELEASE/$image")"
    done
    return "$ok"
}

tendon_budget() {
    image_budget tendon "$TENDON_FLASH_BUDGET_B" "$TENDON_RAM_BUDGET_B"
}

# The e2e image with its live link captured: QEMU's first serial port (USART1) into $OUT/e2e.link.
run_e2e() {
    rm -f "$OUT/e2e.link"
    QEMU_SERIAL="$OUT/e2e.link" run_image e2e 0 '^e2e: [0-9]+ passed, 0 failed$'
}

# host_sim_built: finds host-sim as the root workspace's tests build it (whose cargo settings are
# not the firmware's), into HOST_SIM; building it if needed.
HOST_SIM=""
host_sim_built() {
    HOST_SIM="$(../host-sim/tested.sh)" && echo "$HOST_SIM"
}

# host_sim ARGS...: that host-sim, run from the root, on paths relative to the root.
host_sim() {
    if [[ -z "$HOST_SIM" ]]; then
        echo "host-sim was not built (see the check that builds it)"
        return 1
    fi
    (cd .. && "$HOST_SIM" "$@")
}

# monitor ARGS...: host-sim monitor.
monitor() {
    host_sim monitor "$@"
}

# The e2e image's records, decoded and checked by host-sim against the f64 reference the image
# checks itself against (src/fixture/trajectory.csv): every frame decoded, one record per tick.
link_check() {
    monitor --input "firmware/$OUT/e2e.link" --check-against firmware/src/fixture/trajectory.csv \
        --csv "firmware/$OUT/e2e-link.csv" --quiet >"$OUT/e2e-link.out" 2>&1 || {
        cat "$OUT/e2e-link.out"
        return 1
    }
    cat "$OUT/e2e-link.out"
    grep -Eq "^monitor: $TICKS records, 0 frames refused" "$OUT/e2e-link.out"
}

# The same check on a copy with one byte changed in the middle (never into or out of a 0x00
# delimiter, which would split a frame or join two): the damaged frame must be refused (one
# record fewer) and the check must fail.
link_check_fails() {
    local at byte status=0
    at=$(($(wc -c <"$OUT/e2e.link") / 2))
    byte="$(od -An -tu1 -j "$at" -N1 "$OUT/e2e.link" | tr -d ' ')"
    if ((byte == 0)); then
        at=$((at + 1))
        byte="$(od -An -tu1 -j "$at" -N1 "$OUT/e2e.link" | tr -d ' ')"
    fi
    byte=$((byte ^ 0x80))
    ((byte != 0)) || byte=$((0x40))
    cp "$OUT/e2e.link" "$OUT/e2e-damaged.link"
    printf "\\$(printf '%03o' "$byte")" |
        dd of="$OUT/e2e-damaged.link" bs=1 seek="$at" conv=notrunc status=none
    monitor --input "firmware/$OUT/e2e-damaged.link" \
        --check-against firmware/src/fixture/trajectory.csv --quiet \
        >"$OUT/e2e-damaged.out" 2>&1 || status=$?
    cat "$OUT/e2e-damaged.out"
    if [[ "$status" != 1 ]]; then
        echo "the damaged copy: exit status $status, expected 1 (the check failed)"
        return 1
    fi
    grep -Eq "^monitor: $((TICKS - 1)) records, 1 frames refused" "$OUT/e2e-damaged.out"
}

bench_expected() {
    grep '^bench ' "$OUT/bench.out" >"$OUT/bench.run"
    cat "$OUT/bench.run"
    compare_expected expected/bench.run "$OUT/bench.run"
}

check "cargo fmt --check" cargo fmt --check
# The host tests and their clippy with the bench's two-section cases (`two-section-bench`), which
# the images but the bench are built without.
check "host tests (cargo test --lib --target $HOST --features two-section-bench)" \
    cargo test --lib --target "$HOST" --features two-section-bench
check "host fault scenarios (outage, slipped magnet, power-up off home, stuck sensor, slack cable)" \
    cargo test --lib --target "$HOST" --features two-section-bench scenarios:: -- --nocapture
check "clippy: host lib and tests" \
    cargo clippy --lib --tests --target "$HOST" --features two-section-bench -- -D warnings
check "clippy: target lib and images (with the board image and the live link: the default features)" \
    cargo clippy --release --lib --bins -- -D warnings
# Without the default `board` feature: the QEMU images as expected/ records them (the feature changes
# the library's symbol hashes, and with them the code a little: the estimator image 8 B).
check "build the QEMU images (release, $TARGET)" cargo build --release --no-default-features --bins
# The e2e image alone with the live link (`link`): a feature of the library, so that the other
# images above are built without it, as expected/ records them.
check "build the e2e image with the live link (release, $TARGET)" \
    cargo build --release --no-default-features --features link --bin e2e
# The bench image alone with the two-section robot's cases (`two-section-bench`), as
# expected/bench.run records it: in the library, they change the tendon image's code.
check "build the bench image with the two-section robot (release, $TARGET)" \
    cargo build --release --no-default-features --features two-section-bench --bin bench
check "QEMU selftest: model-core self-checks in f32" run_image selftest 0 '^[0-9]+ passed, 0 failed$'
check "QEMU golden: golden rows from cable lengths, tip within 0.1 mm" run_image golden 0 '^golden: [0-9]+ passed, 0 failed$'
check "QEMU e2e: recorded encoder trajectory against the f64 reference, a record a tick on USART1" run_e2e
TICKS="$(sed -n 's/^e2e: \([0-9]*\) recorded ticks.*/\1/p' "$OUT/e2e.out" 2>/dev/null || true)"
check "build host-sim as the workspace's tests do (host-sim/tested.sh)" host_sim_built
check "live link: host-sim monitor decodes the e2e image's records and checks them against the f64 reference" \
    link_check
check "live link: one byte damaged in a copy: that frame refused, one record fewer, the check fails" \
    link_check_fails
check "QEMU estimator: RTIC sampler at 1 kHz and the production loop with defmt" \
    run_image estimator 0 '^estimator: [0-9]+ ticks, [0-9]+ fresh, 2 injected faults refused$'
check "QEMU estimator: the sampler keeps 1 kHz of virtual time through the cold estimate" \
    grep -E '^estimator: sampling during the cold estimate: [0-9]+ samples in [0-9]+ us of virtual time \(1 kHz\)$' \
    "$OUT/estimator.out"
check "QEMU tendon: golden tendon rows from displacements and a recorded actuation with a slack tendon, f32" \
    run_image tendon 0 '^tendon: [0-9]+ passed, 0 failed$'
check "QEMU bench: instruction counts" run_image bench 0 '^bench case=update_warm'
check "bench instruction counts match expected/bench.run" bench_expected
check "QEMU fault: HardFault reports and exits 1" run_image fault 1 '^hard fault: pc'
check "QEMU panic: panic reports and exits 1" run_image panic 1 'panicked at'
check "QEMU overflow: a stack overflow is a HardFault at the bottom of RAM, reported, exit 1 (flip-link)" \
    run_image overflow 1 '^hard fault: stack overflow: sp 0x[0-9a-f]{8} below the stack.s bottom 0x20000000$'
check "QEMU overflow: the statics above the stack intact" \
    grep -E '^overflow: [0-9]+ frames deep, the statics intact$' "$OUT/overflow.out"
check "estimator image within budget, sizes match expected/estimator.size" budget
check "tendon image within its budget (128 KiB, 32 KiB), sizes match expected/tendon.size" tendon_budget
# The board image needs the `board` feature (a default one), which adds stm32f4xx-hal and
# panic-probe to the library's dependencies; the QEMU images above are built without it.
check "build the board image (build only: it needs the real STM32F405's clock tree)" \
    cargo build --release --bin board

# Any robot: the `robot` image built from a robot file (ROBOT, relative to this directory), run on
# QEMU with its records captured; host-sim solves the same file in f64 at the tip forces the image
# applied (`host-sim reference`) and checks every record against them (`host-sim monitor`). These
# builds come last: another robot rebuilds the library, so the images above are the default
# robot's; each ELF is copied to $OUT/robot-NAME.elf.
robot_end_to_end() {
    local name="$1" file="$2" image="$OUT/robot-$1" status=0
    ROBOT="$file" cargo build --release --no-default-features --features link --bin robot || return 1
    cp "$RELEASE/robot" "$image.elf"
    rm -f "$image.link"
    QEMU_SERIAL="$image.link" ./qemu.sh "$image.elf" >"$image.out" 2>&1 || status=$?
    grep -Ev '^(applied|tick) ' "$image.out"
    if [[ "$status" != 0 ]] || ! grep -Eq '^robot: [0-9]+ passed, 0 failed$' "$image.out"; then
        echo "robot-$name: exit status $status, or not every tick passed"
        return 1
    fi
    {
        echo "tick,force_x_n,force_y_n,force_z_n"
        sed -n 's/^applied tick=\([0-9]*\) force_n=\(.*\)$/\1,\2/p' "$image.out"
    } >"$image.forces.csv"
    host_sim reference "firmware/$file" \
        --forces "firmware/$image.forces.csv" --out "firmware/$image.reference.csv" || return 1
    monitor --input "firmware/$image.link" --check-against "firmware/$image.reference.csv" --quiet
}

# must_not_build NAME PATTERN [VARIABLE]: a robot that does not fit is a build error naming what
# does not fit. The robot file is $OUT/NAME.toml (written by the caller), given in VARIABLE (ROBOT,
# or TENDON_ROBOT for the tendon image's).
must_not_build() {
    local name="$1" pattern="$2" variable="${3:-ROBOT}" status=0
    env "$variable=$OUT/$name.toml" cargo build --release --lib --no-default-features \
        >"$OUT/$name.build" 2>&1 || status=$?
    grep -E "$pattern" "$OUT/$name.build" | head -n 3
    if [[ "$status" == 0 ]]; then
        echo "$name: the build succeeded"
        return 1
    fi
    grep -Eq "$pattern" "$OUT/$name.build" || {
        tail -n 20 "$OUT/$name.build"
        echo "$name: no error matching /$pattern/"
        return 1
    }
}

# The default robot with a fourth cable (its drive lists extended to match): the sampler reads three.
sed -e '0,/^\[drive\]/s//[[cable]]\nangle_deg = 60.0\nradius_m = 0.01\n\n[drive]/' \
    -e 's/^home_lengths_m = \[\(.*\)\]/home_lengths_m = [\1, 0.38]/' \
    -e 's/^zero_offset_counts = \[\(.*\)\]/zero_offset_counts = [\1, 0]/' \
    -e 's/^reel_in_with_counts = \[\(.*\)\]/reel_in_with_counts = [\1, false]/' \
    robots/bench.toml >"$OUT/four-cables.toml"
# A drive whose sensor turns more than the sampler can follow between two samples.
sed -e 's/^max_cable_speed_m_per_s = .*/max_cable_speed_m_per_s = 0.5/' robots/bench.toml \
    >"$OUT/too-fast.toml"
# No [controller] table.
sed -e '/^\[controller\]/,$d' robots/bench.toml >"$OUT/no-controller.toml"
# The tendon robot with a fourth tendon.
sed -e '0,/^\[actuation\]/s//[[tendon]]\nangle_deg = 60.0\nradius_m = 0.01\n\n[actuation]/' \
    -e 's/^tensions_n = \[\(.*\)\]/tensions_n = [\1, 0.0]/' \
    robots/tendon_bench.toml >"$OUT/four-tendons.toml"
check "robot file: four cables is a build error naming the 4 cables and the capacity, 3" \
    must_not_build four-cables '4 \[\[cable\]\] tables; the firmware reads exactly 3 cables'
check "robot file: a drive too fast for the sampler is a build error naming the drive's keys" \
    must_not_build too-fast "drive turns the sensor too far in a sampling period"
check "robot file: no [controller] table is a build error naming it" \
    must_not_build no-controller 'the firmware needs its \[drive\] and \[controller\] tables'
check "tendon robot file: four tendons is a build error naming the 4 tendons and the capacity, 3" \
    must_not_build four-tendons '4 \[\[tendon\]\] tables; the tendon image drives exactly 3' TENDON_ROBOT
check "QEMU robot: the default robot file along its load path, records checked by host-sim in f64" \
    robot_end_to_end bench robots/bench.toml
check "QEMU robot: robots/two_section.toml (27 nodes) along its load path, checked by host-sim in f64" \
    robot_end_to_end two_section robots/two_section.toml

printf '\n== summary\n'
printf '%s\n' "${summary[@]}"
printf 'firmware: %d passed, %d failed\n' "$passed" "$failed"
if ((failed)); then
    printf 'failed: %s\n' "${failures[@]}" >&2
    exit 1
fi
