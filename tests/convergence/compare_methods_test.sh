#!/usr/bin/env bash
# compare_methods_test.sh AFTERGLOW WORK: `afterglow compare-methods` at 48x48 through the short
# edit script (tests/convergence/compare_edits_short.lua: cube slide, light move, wall recolour),
# every variant, with fixed per-frame counts (--frame-ms 0: the frames counted do not depend on
# the machine's speed), 200 IIM texels a frame (so that the IIM can settle within the script's
# last 11 frames), and smaller VPL shadow maps and fewer irradiance-cache rays (to keep it short).
# Then tests/convergence/check_compare_methods.py holds every method to its settled error and to
# the frames it takes to settle after the last edit. Exit 77 (skipped) without a GL context or
# without Debian's python3.
set -uo pipefail
bin="$1"; work="$2"
"$bin" glinfo >/dev/null 2>&1 || { echo "no GL context: skipped"; exit 77; }
[ -x /usr/bin/python3 ] || { echo "no /usr/bin/python3: skipped"; exit 77; }
mkdir -p "$work"
"$bin" compare-methods scenes/compare.json --script tests/convergence/compare_edits_short.lua \
    --frames 36 --size 48x48 --frame-ms 0 --set gather.texels_per_frame=200 \
    --set vpl.map_size=64 --set rc.theta_strata=8 --set rc.phi_strata=32 --ref-spp 64 --pt-spp 4 \
    --cache "$work/compare-cache" --out "$work/compare-methods" -q || exit 1
for f in csv md frames.csv png; do
    [ -s "$work/compare-methods.$f" ] || { echo "missing output $work/compare-methods.$f"; exit 1; }
done
/usr/bin/python3 tests/convergence/check_compare_methods.py "$work/compare-methods.csv"
