#!/usr/bin/env bash
# bright_render_test.sh AFTERGLOW: a lamp of 1e11 W/sr lights pixels far above half float's
# 65504; the EXR must keep them finite (it used to hold +Inf). Exit 77 (skipped) without a GL
# context or without oiiotool to read the statistics back.
set -uo pipefail
bin="$1"
d=$(mktemp -d); trap 'rm -rf "$d"' EXIT
command -v oiiotool >/dev/null || { echo "no oiiotool: skipped"; exit 77; }
"$bin" glinfo >/dev/null 2>&1 || { echo "no OSMesa context: skipped"; exit 77; }
sed 's/"intensity": \[400000, 340000, 240000\]/"intensity": [1e11, 1e11, 1e11]/' \
  scenes/cornell.json > "$d/bright.json"
grep -q '1e11' "$d/bright.json" || { echo "could not make the bright scene" >&2; exit 1; }
"$bin" render "$d/bright.json" -o "$d/b.exr" --frames 2 --size 32x24 -q || exit 1
stats=$(oiiotool --stats "$d/b.exr") || exit 1
echo "$stats" | grep -E "Max:|NanCount|InfCount"
echo "$stats" | grep -Eq "NanCount: 0 0 0" || { echo "NaN pixels" >&2; exit 1; }
echo "$stats" | grep -Eq "InfCount: 0 0 0" || { echo "infinite pixels" >&2; exit 1; }
# Pixels above the half-float range are really there.
max=$(echo "$stats" | sed -n 's/.*Max: *\([^ ]*\).*/\1/p' | head -1)
awk -v m="$max" 'BEGIN { exit !(m > 65504) }' || { echo "max $max is not above 65504" >&2; exit 1; }
# compare refuses images with NaN or Inf, naming the file and the count.
oiiotool "$d/b.exr" --mulc 1e30 --mulc 1e30 -d float -o "$d/inf.exr" || exit 1
out=$("$bin" compare "$d/b.exr" "$d/inf.exr" 2>&1); code=$?
echo "$out"
[ $code -eq 1 ] || { echo "compare exit $code, expected 1" >&2; exit 1; }
echo "$out" | grep -q "inf.exr: [0-9]* NaN or infinite pixel values" || exit 1
echo "bright render ok"
