#!/usr/bin/env bash
# fidelity_edges_test.sh AFTERGLOW: the AIM's boundary-corrected density (issue #12,
# docs/fidelity.md "The kNN disc at chart edges") at CI size. `afterglow fidelity` on the Cornell
# box at 48², stage (a): the AIM's radiance at every texel centre against path-traced outgoing
# radiance at the same point, summed over the texels on the rim of the floor and the three walls
# (centres snapped onto a chart edge, where the room's creases are) and over the rest, each texel
# weighted by its area (so the finer texels of a refined layout near the cube count for the floor
# they cover, not 16 times over).
# Without the correction (aim.boundary_correction=false) the rim reads about half and the rest
# 10% high; measured values below. Extra arguments go to `fidelity` (e.g. --set seed=2).
# Exit 77 (skipped) without a GL context.
set -uo pipefail
bin="$1"
shift
d=$(mktemp -d); trap 'rm -rf "$d"' EXIT
"$bin" glinfo >/dev/null 2>&1 || { echo "no OSMesa context: skipped"; exit 77; }
"$bin" fidelity scenes/cornell.json --size 48x48 --pt-paths 256 --reference-rays 64 \
  --pixel-rays 16 "$@" --csv "$d/f.csv" >/dev/null || { echo "fidelity failed" >&2; exit 1; }
python3 - "$d/f.csv" <<'PY'
import csv, sys

rows = list(csv.reader(open(sys.argv[1])))
start = next(i for i, r in enumerate(rows) if r and r[0] == "record")
head = rows[start]
texels = [dict(zip(head, r)) for r in rows[start + 1:] if len(r) == len(head)]

def lum(t, p):
    return sum(w * float(t[p + c]) for w, c in ((0.2126, "_r"), (0.7152, "_g"), (0.0722, "_b")))

sums = {"rim": [0.0, 0.0, 0], "inside": [0.0, 0.0, 0]}
for obj in ("floor", "back_wall", "left_wall", "right_wall"):
    ts = [t for t in texels if t["object"] == obj]
    axes = [a for a in "xyz" if max(float(t[a]) for t in ts) - min(float(t[a]) for t in ts) > 1]
    lo = {a: min(float(t[a]) for t in ts) for a in axes}
    hi = {a: max(float(t[a]) for t in ts) for a in axes}
    for t in ts:
        rim = any(min(float(t[a]) - lo[a], hi[a] - float(t[a])) < 5.0 for a in axes)
        s = sums["rim" if rim else "inside"]
        s[0] += float(t["area"]) * lum(t, "aim")
        s[1] += float(t["area"]) * lum(t, "pt_radiance")
        s[2] += 1
failed = []

def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failed.append(what)

# Measured (docs/fidelity.md): rim 1.068 / 1.114 with photon seeds 1 / 2, 0.557 without the
# correction; the rest 1.002 / 1.027, 1.096 without (uniform layout, one photon set). At the
# tiled defaults with 16 sets, area-weighted: rim 1.041 / 1.065 / 1.036 over seeds 1-3, the rest
# 1.030 / 1.018 / 1.027 (counting texels instead, the contact's 16-times finer texels gave 1.088). The rim's excess is the cut disc's mean
# standing for the density at its centroid, inside the chart, where the light is brighter
# (docs/fidelity.md "The rims' overshoot"; aim.boundary_linear removes it, off by default); the
# bounds leave room for it and for the seed-to-seed spread, and still fail the uncorrected AIM.
rim = sums["rim"][0] / sums["rim"][1]
inside = sums["inside"][0] / sums["inside"][1]
check(0.85 < rim < 1.2, f"texels on chart edges: AIM / pt radiance {rim:.3f} over {sums['rim'][2]} (0.85-1.2)")
check(abs(inside - 1) < 0.06, f"other texels: AIM / pt radiance {inside:.3f} over {sums['inside'][2]} (within 6%)")
sys.exit(1 if failed else 0)
PY
