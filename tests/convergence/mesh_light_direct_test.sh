#!/usr/bin/env bash
# mesh_light_direct_test.sh AFTERGLOW WORK: issue #14, mesh-light samples over frames. A tilted
# emissive box (a mesh light) over a floor, a small blocker between them casting a penumbra; the
# camera sees only the floor (no edges, so the pixels' single sample against pt's many does not
# count). While the scene stands still, the frame moves the light's samples within their strata
# and averages the direct term: after 64 frames it must agree with pt's direct term within pt's
# own noise (relMSE of two seeds), and the single frame (16 fixed samples: banded shadows) must be
# several times worse. Exit 77 (skipped) without a GL context.
set -uo pipefail
bin="$1"; work="$2/mesh_light_direct"
"$bin" glinfo >/dev/null 2>&1 || { echo "no GL context: skipped"; exit 77; }
mkdir -p "$work"
cat > "$work/penumbra.json" <<'JSON'
{
    "name": "mesh_light_penumbra",
    "camera": {"eye": [0, 1, 0], "target": [0, 0, 0], "up": [0, 0, -1], "fov_y": 60,
               "resolution": [64, 64]},
    "materials": {
        "white": {"albedo": [0.7, 0.7, 0.7]},
        "lamp": {"albedo": [0.5, 0.5, 0.5], "emission": [40, 40, 40]}
    },
    "lights": [],
    "objects": [
        {"name": "floor", "material": "white", "shape": {"type": "quad", "size": [6, 6]}},
        {"name": "blocker", "material": "white", "shape": {"type": "box", "size": [0.5, 0.05, 0.5]},
         "transform": {"translate": [0, 1.3, 0]}},
        {"name": "lamp", "material": "lamp", "shape": {"type": "box", "size": [0.6, 0.1, 0.6]},
         "transform": {"rotate": {"axis": [0, 0, 1], "degrees": 30}, "translate": [0.4, 1.8, 0]}}
    ],
    "settings": {"caustics": {"photons": 0}, "direct": {"area_light_samples": 16}}
}
JSON
scene="$work/penumbra.json"
for seed in 1 2; do
  "$bin" reference "$scene" --method pt -o "$work/pt$seed.exr" --spp 256 --seed $seed -q >/dev/null || exit 1
done
for frames in 1 64; do
  "$bin" render "$scene" -o "$work/frame$frames.exr" -n $frames --aov -q >/dev/null || exit 1
done
relmse() {
  "$bin" compare "$1" "$2" --json | sed -n 's/.*"relmse":\([0-9.eE+-]*\).*/\1/p'
}
noise=$(relmse "$work/pt2.direct.exr" "$work/pt1.direct.exr")
one=$(relmse "$work/frame1.direct.exr" "$work/pt1.direct.exr")
many=$(relmse "$work/frame64.direct.exr" "$work/pt1.direct.exr")
echo "direct term relMSE against pt: 1 frame $one, 64 frames $many; pt seed 2 against seed 1 $noise"
awk -v n="$noise" -v a="$one" -v b="$many" 'BEGIN {
  if (n == "" || a == "" || b == "") { print "a metric is missing"; exit 1 }
  if (!(b <= n)) { print "64 frames: relMSE " b " above the reference noise " n; exit 1 }
  if (!(4 * b <= a)) { print "64 frames (" b ") not 4x better than 1 frame (" a ")"; exit 1 }
}'
