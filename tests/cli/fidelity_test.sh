#!/usr/bin/env bash
# fidelity_test.sh AFTERGLOW: the indirect term's error budget on the Cornell box at CI size
# (docs/fidelity.md, issue #12). Two 48² pt references (256 spp, about a second each), then
# `afterglow fidelity` twice: at Larsen's 111 mm texels, uniform, one photon set, for the gather
# stage (Gautron's Table 4.1 ordering, light through glass) and at the defaults for the image
# stages (the IIM refined to gather.refine_passes, without stage b's variants); then the settled frame as shown (one sample per pixel a frame, the
# running mean of 64 sub-pixel offsets: frame.accumulate_frames) against pt. The bounds come from
# measured values and their spread over seeds (docs/fidelity.md); exit 77 (skipped) without a GL
# context.
set -uo pipefail
bin="$1"
d=$(mktemp -d); trap 'rm -rf "$d"' EXIT
"$bin" glinfo >/dev/null 2>&1 || { echo "no OSMesa context: skipped"; exit 77; }
for seed in 1 2; do
  "$bin" reference scenes/cornell.json --method pt --size 48x48 --spp 256 --seed $seed \
    -o "$d/pt$seed.exr" >/dev/null 2>&1 || { echo "reference failed" >&2; exit 1; }
done
"$bin" fidelity scenes/cornell.json --set lightmap.texel_size=111 --set lightmap.refine_factor=1 \
  --set lightmap.refine_tile=0 --set photons.refine_layers=1 --size 48x48 --pt-paths 64 \
  --reference-rays 1024 --pixel-rays 128 --csv "$d/gather.csv" >/dev/null ||
  { echo "fidelity (111 mm) failed" >&2; exit 1; }
"$bin" fidelity scenes/cornell.json --size 48x48 --pt-paths 64 --reference-rays 1024 \
  --pixel-rays 1024 --no-variants --reference "$d/pt1.exr" --csv "$d/image.csv" >/dev/null ||
  { echo "fidelity failed" >&2; exit 1; }
# The settled frame as shown (every texel refined: 2000 texels a frame settles in ~25 frames;
# then 64 frames of sub-pixel offsets).
"$bin" render scenes/cornell.json --size 48x48 --frames 150 --aov \
  --set gather.texels_per_frame=2000 -q -o "$d/frame.exr" >"$d/render.log" 2>&1 ||
  { echo "render failed" >&2; exit 1; }
grep -q "mean of the last 64 frames (complete; converged: yes)" "$d/render.log" ||
  { echo "the frame is not the complete mean of a converged scene:" >&2; cat "$d/render.log" >&2; exit 1; }
relmse() { "$bin" compare "$1" "$2" 2>/dev/null | awk '/^relmse/ {print $2}'; }
frame_pt=$(relmse "$d/frame.exr" "$d/pt1.exr")
pt_pt=$(relmse "$d/pt2.exr" "$d/pt1.exr")
frame_pt_ind=$(relmse "$d/frame.indirect.exr" "$d/pt1.indirect.exr")
pt_pt_ind=$(relmse "$d/pt2.indirect.exr" "$d/pt1.indirect.exr")
python3 - "$d/gather.csv" "$d/image.csv" "$frame_pt" "$pt_pt" "$frame_pt_ind" "$pt_pt_ind" <<'PY'
import csv, sys

def rows(path):
    out = {}
    with open(path) as f:
        for r in csv.reader(f):
            if not r:
                break  # the per-texel table follows
            if r[0] in ("a", "b", "c", "d", "e"):
                out[(r[0], r[1], r[2], r[3])] = (float(r[5]), float(r[6]), float(r[7]))
    return out

g, im = rows(sys.argv[1]), rows(sys.argv[2])
failed = []

def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failed.append(what)

# Gautron's Table 4.1 with our gather (111 mm texels; measured 19.1 / 11.0 / 5.2% GL and
# 19.1 / 11.1 / 4.9% CPU at 1024 reference rays): the order, and stretch (border pixels stretched
# perpendicular to their edge, clamp-to-edge) within Gautron's 5.8%. The radial stretch (same
# azimuth; 6.15% GL, 6.0% CPU) fails that bound.
for b in ("gl", "cpu"):
    none, ren, st, radial = (g[("b", f"{b}_plane_{c}", "full_black", "all")][1]
                             for c in ("none", "renormalize", "stretch", "stretch_radial"))
    check(none > ren > st, f"{b} plane RMS none {none:.3f} > renormalize {ren:.3f} > stretch {st:.3f}")
    check(0.15 < none < 0.23 and st <= 0.058, f"{b} plane RMS none {none:.3f}, stretch {st:.3f} (<= 0.058)")
    check(st < radial, f"{b} plane RMS stretch {st:.3f} < radial stretch {radial:.3f}")
# The band (border_correction=band, the default since session 14): the directions beyond the
# plane rendered through a second, wider view instead of assumed like its border. Table 4.1 with
# it (111 mm, this test): GL 3.9% -> 1.2% RMS, CPU 3.6% -> 0.2%; held to half the stretch's.
band_cpu = g[("b", "cpu_plane_band", "full_black", "all")][1]
band_gl = g[("b", "gl_plane_band", "full_black", "all")][1]
st_cpu = g[("b", "cpu_plane_stretch", "full_black", "all")][1]
st_gl = g[("b", "gl_plane_stretch", "full_black", "all")][1]
check(band_cpu < 0.5 * st_cpu, f"cpu plane RMS band {band_cpu:.3f} < half the stretch's {st_cpu:.3f}")
check(band_gl < 0.5 * st_gl, f"gl plane RMS band {band_gl:.3f} < half the stretch's {st_gl:.3f}")
# Light through the glass sphere counts: without specular bounces the gather loses 5% (measured
# 0.949); with them the pipeline's gather matches the full-hemisphere one (measured 1.000).
black = g[("b", "full_black", "full", "all")][0]
check(black < 0.97, f"glass black to the gather reads {black:.4f} of the full gather (< 0.97)")
pipe = g[("b", "pipeline", "full", "all")][0]
check(abs(pipe - 1) < 0.02, f"pipeline gather / full gather {pipe:.4f} (within 2%)")
# The IIM as the camera sees it against gathering at every pixel (measured 0.996 at 55.5 mm,
# 0.957 at 111 mm; 0.997 / 0.999 / 1.000 over photon seeds 1-3 at the tiled defaults): within 2%.
frame = im[("d", "frame", "pixel_gather", "all")][0]
check(abs(frame - 1) < 0.02, f"frame / per-pixel gather {frame:.4f} (within 2%)")
# Against pt at 256 spp: measured 0.997 / 1.009 / 1.013 over seeds 1-3 on the uniform layout,
# 0.987 / 0.985 / 0.986 at the tiled defaults (a 256-spp seed's own mean is within about 1%);
# before issue #12 0.929.
pt = im[("e", "frame", "pt_image", "all")][0]
check(abs(pt - 1) < 0.035, f"frame indirect / pt indirect {pt:.4f} (within 3.5%)")
# Refinement (16 gathers per settled texel): the back wall as the camera sees it against
# per-pixel gathering at 1024 rays, relMSE 0.0007 / 0.0009 / 0.0008 over photon seeds 1-3 at the
# defaults (tiled layout, 16 photon sets); one gather per texel (gather.refine_passes=1) 0.0050 /
# 0.0051. At 256 rays a pixel the per-pixel gather's own noise on the 16 sets' finer AIMs was most
# of the figure (0.0145 refined; 0.0088 with one photon set).
wall = im[("d", "frame", "pixel_gather", "back_wall")][2]
check(wall < 0.0025, f"back wall: frame / per-pixel gather relMSE {wall:.4f} (< 0.0025)")
# The frame as shown against pt, above the reference's own noise (issue #12: relMSE <= 0.010 above
# it, full frame and indirect term). A pt seed's relMSE against the truth is half the seed-to-seed
# relMSE (0.066 full, 0.125 indirect at 256 spp; 0.064-0.070 over seed pairs), so the excess is
# relMSE(frame, pt1) - relMSE(pt2, pt1) / 2. Measured: full 0.000 (0.0015 against seed 2),
# indirect -0.004 (+0.001); with one sample at each pixel centre (frame.accumulate_frames=1) the
# outlines alone give 0.021 / 0.014, and 2x2 supersampling (the check before) 0.010.
for name, test, noise in (("full frame", float(sys.argv[3]), float(sys.argv[4])),
                          ("indirect", float(sys.argv[5]), float(sys.argv[6]))):
    excess = test - noise / 2
    check(excess <= 0.010, f"{name} / pt relMSE {test:.4f}, above pt's noise ({noise / 2:.4f}) "
          f"{excess:+.4f} (<= 0.010)")
sys.exit(1 if failed else 0)
PY
