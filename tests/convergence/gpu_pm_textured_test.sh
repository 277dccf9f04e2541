#!/usr/bin/env bash
# gpu_pm_textured_test.sh AFTERGLOW WORK: issue #14, textured albedo for GPU photons. gpu_pm's
# indirect term on the checker-textured Cornell box (photons take the texel's albedo where they
# bounce) must match pt's single-bounce reference as closely as gpu_pm does on the untextured box
# at the same size and budgets (relMSE within 1.2x of it). Photons bouncing with the white base
# albedo (before this issue: 1.33x the untextured error) fail it. 32x32, 16 frames: ~5 s, so the
# errors are large; what counts is their ratio (textured 0.86x).
# Exit 77 (skipped) without a GL context.
set -uo pipefail
bin="$1"; work="$2/gpu_pm_textured"
"$bin" glinfo >/dev/null 2>&1 || { echo "no GL context: skipped"; exit 77; }
mkdir -p "$work"
relmse() {
  "$bin" compare "$1" "$2" --json | sed -n 's/.*"relmse":\([0-9.eE+-]*\).*/\1/p'
}
for scene in cornell cornell_textured; do
  "$bin" reference scenes/$scene.json -m pt --indirect-bounces 1 --spp 512 --size 32x32 \
    -o "$work/$scene.pt.exr" -q >/dev/null || exit 1
  "$bin" render scenes/$scene.json --indirect gpu_pm -n 16 --size 32x32 --aov \
    -o "$work/$scene.exr" -q >/dev/null 2>&1 || exit 1
done
plain=$(relmse "$work/cornell.indirect.exr" "$work/cornell.pt.indirect.exr")
textured=$(relmse "$work/cornell_textured.indirect.exr" "$work/cornell_textured.pt.indirect.exr")
echo "gpu_pm indirect relMSE against pt: untextured $plain, textured $textured"
awk -v p="$plain" -v t="$textured" 'BEGIN {
  if (p == "" || t == "") { print "a metric is missing"; exit 1 }
  if (!(t <= 1.2 * p)) { print "textured " t " above 1.2x the untextured " p; exit 1 }
}'
