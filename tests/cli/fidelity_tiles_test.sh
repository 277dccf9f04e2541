#!/usr/bin/env bash
# fidelity_tiles_test.sh AFTERGLOW: density within a chart (lightmap.refine_tile, issue #12 item 4,
# docs/fidelity.md "Density within a chart") at CI size. The Cornell floor cut into tiles of one
# base texel, the tiles within a texel of the dynamic cube and sphere at 13.875 mm
# (refine_factor 4), the rest of the floor at 55.5 mm: (1) the atlas holds well under the
# texels of refining the whole floor (`afterglow info`; without tiles the count is the same and
# this fails), and (2) `afterglow fidelity` at 48², stage (d), the frame's indirect term against
# gathering at every pixel, resolves the patch the glass ball focuses beside its contact
# (uniform 55.5 mm texels fail it; measured values below). Exit 77 (skipped) without GL.
set -uo pipefail
bin="$1"
d=$(mktemp -d); trap 'rm -rf "$d"' EXIT
"$bin" glinfo >/dev/null 2>&1 || { echo "no OSMesa context: skipped"; exit 77; }
fine=(--set lightmap.refine_factor=4 --set lightmap.refine_budget=10 --set lightmap.refine_reach=0
      --set photons.refine_layers=1)
texels() { "$bin" info scenes/cornell.json "$@" | awk '$1 == "texels" { print $2 }'; }
whole=$(texels "${fine[@]}" --set lightmap.refine_tile=0) tiled=$(texels "${fine[@]}" --set lightmap.refine_tile=1) uniform=$(texels --set lightmap.refine_factor=1)
"$bin" fidelity scenes/cornell.json --size 48x48 --pt-paths 4 --reference-rays 64 \
  --pixel-rays 256 "${fine[@]}" --set lightmap.refine_tile=1 --csv "$d/f.csv" >/dev/null ||
  { echo "fidelity failed" >&2; exit 1; }
python3 - "$d/f.csv" "$uniform" "$whole" "$tiled" <<'PY'
import csv, sys

uniform, whole, tiled = (int(v) for v in sys.argv[2:5])
rows = {}
with open(sys.argv[1]) as f:
    for r in csv.reader(f):
        if not r:
            break  # the per-texel table follows
        if r[0] == "d" and r[1] == "frame":
            rows[r[3]] = (float(r[5]), float(r[7]))
failed = []

def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failed.append(what)

# Texels: uniform 659, the whole floor and cube at x4 2894, tiles 1888 (0.65 of it).
check(tiled < 0.75 * whole and tiled > uniform,
      f"texels: tiled {tiled}, whole charts {whole}, uniform {uniform} (tiled < 0.75 x whole)")
# The floor beside the glass sphere: relMSE tiles 0.0031, ratio 0.976 (uniform 0.147, whole floor
# x2 0.012, x4 0.0028; cli.fidelity_density).
rel = rows["floor/near:sphere"][1]
check(rel < 0.05, f"floor beside the sphere: frame / per-pixel gather relMSE {rel:.4f} (< 0.05)")
ratio = rows["floor/near:sphere"][0]
check(abs(ratio - 1) < 0.05, f"floor beside the sphere: frame / per-pixel gather {ratio:.4f} (within 5%)")
whole_image = rows["all"][0]  # tiles 1.0024
check(abs(whole_image - 1) < 0.02, f"whole image: frame / per-pixel gather {whole_image:.4f} (within 2%)")
sys.exit(1 if failed else 0)
PY
