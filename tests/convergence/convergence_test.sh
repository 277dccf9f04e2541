#!/usr/bin/env bash
# convergence_test.sh AFTERGLOW: the small convergence run of the Cornell scene (48x48, small
# budgets, reference cached in the build folder). Exit 77 (skipped) without a GL context or
# without Debian's python3.
set -uo pipefail
bin="$1"; work="$2"
"$bin" glinfo >/dev/null 2>&1 || { echo "no GL context: skipped"; exit 77; }
[ -x /usr/bin/python3 ] || { echo "no /usr/bin/python3: skipped"; exit 77; }
mkdir -p "$work"
common=(--size 48x48 --frames 90 --ref-spp 16 --ref-photons 200000 --cache "$work/cache" --plot "" -q)
"$bin" converge scenes/cornell.json --script "" --csv "$work/static.csv" "${common[@]}" || exit 1
"$bin" converge scenes/cornell.json --script scenes/cornell_move_cube.lua --csv "$work/selective.csv" "${common[@]}" || exit 1
"$bin" converge scenes/cornell.json --script scenes/cornell_move_cube.lua --baseline full --csv "$work/full.csv" "${common[@]}" || exit 1
/usr/bin/python3 tests/convergence/check_convergence.py "$work/static.csv" "$work/selective.csv" "$work/full.csv" 0.15 20
