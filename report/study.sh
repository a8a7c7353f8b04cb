#!/usr/bin/env bash
# The accuracy-vs-cost study: report/accuracy_cost.md, .csv, pareto.svg/.png and (the tendon scenes)
# tendon_pareto.svg/.png.
#   report/study.sh            the full study, written into report/
#   report/study.sh --quick    CI's quick mode, written into target/study-quick/
# Options: --out DIR (where to write). Exits non-zero if a check of the study fails.
#
# micromath is a compile-time feature of model-core (`fast-math`), so its rows come from a second
# build of host-sim, run first and merged into the report by the ordinary build.
set -euo pipefail
cd "$(dirname "$0")/.."

quick=()
out=""
while [ $# -gt 0 ]; do
    case "$1" in
        --quick) quick=(--quick) ;;
        --out) out="$2"; shift ;;
        *) echo "usage: report/study.sh [--quick] [--out DIR]" >&2; exit 2 ;;
    esac
    shift
done
if [ -z "$out" ]; then
    if [ ${#quick[@]} -gt 0 ]; then out=target/study-quick; else out=report; fi
fi
mkdir -p "$out" target
rows="target/study-micromath-rows.json"

# The full study times its rows: release builds. The quick mode (CI's, after the tests) checks the
# study's findings with host-sim as the workspace's tests built it (host-sim/tested.sh) and the
# fast-math build in the same profile, so no dependency is built again in release.
if [ ${#quick[@]} -gt 0 ]; then profile=(--profile test); else profile=(--release); fi

echo "== f32 micromath rows (host-sim built with model-core's fast-math feature)"
cargo run "${profile[@]}" --quiet -p host-sim --features fast-math -- \
    study "${quick[@]}" --fast-math-only --rows-out "$rows"

echo "== the study, micromath rows merged, into $out"
if [ ${#quick[@]} -gt 0 ]; then
    # After the fast-math build: finding the tests' binary puts it back in place of that one.
    "$(host-sim/tested.sh)" study "${quick[@]}" --merge "$rows" --out "$out"
else
    cargo run --release --quiet -p host-sim -- study --merge "$rows" --out "$out"
fi
