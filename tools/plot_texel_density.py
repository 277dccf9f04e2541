#!/usr/bin/python3
"""Plot region error against lightmap texels from `afterglow fidelity --csv` runs.

usage: tools/plot_texel_density.py OUT.png LABEL:TEXELS:FIDELITY.csv [...]
       tools/plot_texel_density.py OUT.png SUMMARY.csv

One point per run and region: x = the atlas's texels (`afterglow info` prints them), y = stage
(e), the frame's indirect term against the pt reference, as a ratio of means. LABEL names the
layout; labels starting with "uniform" are drawn as hollow markers joined by a dashed line,
others (adaptive density) as filled markers joined by a solid line. A SUMMARY.csv has the columns
layout,texels,region,ratio (docs/images/texel_density.csv). The ±5% band is issue #12's bar for
regions. Uses Debian's python3-matplotlib (the system interpreter, hence the shebang).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

REGIONS = [("all", "whole image"), ("floor/shadow:sphere", "floor in the sphere's shadow"),
           ("floor/shadow:cube", "floor in the cube's shadow"), ("cube", "cube")]


def region_ratios(path):
    out = {}
    with open(path, newline="") as f:
        for row in csv.reader(f):
            if not row:
                break  # the per-texel table follows
            if row[:3] == ["e", "frame", "pt_image"]:
                out[row[3]] = float(row[5])
    if not out:
        sys.exit(f"{path}: no stage (e) rows (expected an afterglow fidelity CSV run with "
                 "--reference)")
    return out


def main(argv):
    if len(argv) < 2 or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    out, runs = argv[0], []
    if len(argv) == 2 and ":" not in argv[1]:
        by_layout = {}
        with open(argv[1], newline="") as f:
            for r in csv.DictReader(f):
                try:
                    key = (r["layout"], int(r["texels"]))
                    by_layout.setdefault(key, {})[r["region"]] = float(r["ratio"])
                except (KeyError, ValueError) as e:
                    sys.exit(f"{argv[1]}: expected columns layout,texels,region,ratio ({e})")
        runs = [(label, texels, r) for (label, texels), r in by_layout.items()]
    for spec in argv[1:] if not runs else []:
        parts = spec.split(":", 2)
        if len(parts) != 3:
            sys.exit(f"'{spec}': expected LABEL:TEXELS:FIDELITY.csv")
        runs.append((parts[0], int(parts[1]), region_ratios(parts[2])))
    fig, ax = plt.subplots(figsize=(7.5, 4.4), dpi=110)
    ax.axhspan(0.95, 1.05, color="0.9", zorder=0, label="±5% (regions)")
    ax.axhline(1.0, color="0.5", linewidth=0.8)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, (region, name) in enumerate(REGIONS):
        for uniform in (True, False):
            pts = sorted((t, r[region]) for label, t, r in runs
                         if label.startswith("uniform") == uniform and region in r)
            if not pts:
                continue
            ax.plot([p[0] for p in pts], [p[1] for p in pts], color=colors[i],
                    linestyle="--" if uniform else "-", marker="o",
                    markerfacecolor="none" if uniform else colors[i],
                    label=f"{name} ({'uniform' if uniform else 'adaptive'})")
    for label, t, r in runs:
        ax.annotate(label, (t, r.get("floor/shadow:sphere", 1.0)), fontsize=7,
                    textcoords="offset points", xytext=(4, 4))
    ax.set_xscale("log")
    ax.set_xlabel("lightmap texels (settle time grows in proportion; frame time does not)")
    ax.set_ylabel("frame indirect / pt indirect")
    ax.set_title("Cornell 96²: region error against texels, uniform and adaptive density")
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
