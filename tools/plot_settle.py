#!/usr/bin/python3
"""Plot settle time against scene size from an `afterglow bench settle` CSV.

usage: tools/plot_settle.py OUT.png BENCH.csv

Log-log: triangles on x, seconds from the edit until the indirect error is back within 10% of its
settled value on y. One line per mode (selective, full, full-budget) through the median over the
scene's scripts; each script's run is a dot. Runs that did not settle are left out.
Uses Debian's python3-matplotlib (the system interpreter, hence the shebang).
"""
import csv
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) != 2 or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    out, path = argv
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for key in ("mode", "triangles", "settle_s"):
        if rows and key not in rows[0]:
            sys.exit(f"{path}: missing column '{key}' (expected an afterglow bench settle CSV)")
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
    modes = []
    for r in rows:
        if r["mode"] not in modes:
            modes.append(r["mode"])
    for mode in modes:
        by_size = {}
        for r in rows:
            if r["mode"] == mode and r["settle_s"]:
                by_size.setdefault(int(r["triangles"]), []).append(max(float(r["settle_s"]), 1e-3))
        if not by_size:
            continue
        sizes = sorted(by_size)
        (line,) = ax.plot(sizes, [statistics.median(by_size[s]) for s in sizes], marker="o",
                          label=mode, linewidth=1.4)
        for s in sizes:
            ax.scatter([s] * len(by_size[s]), by_size[s], color=line.get_color(), s=10, alpha=0.5)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("scene size (triangles)")
    ax.set_ylabel("settle time after the edit (s)")
    target = rows[0].get("frame_ms_target") if rows else None
    ax.set_title(f"back within 10% of the settled indirect error (--frame-ms {target})")
    ax.grid(True, which="both", alpha=0.3)
    if modes:
        ax.legend()
    fig.tight_layout()
    tmp = os.path.join(os.path.dirname(os.path.abspath(out)), "." + os.path.basename(out) + ".tmp.png")
    fig.savefig(tmp)
    os.replace(tmp, out)  # atomic
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
