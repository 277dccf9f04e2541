#!/usr/bin/python3
"""Plot the indirect error of every method against wall-clock time from `afterglow compare-methods`.

usage: tools/plot_compare_methods.py OUT.png PREFIX.frames.csv [--title TEXT]

Left: relMSE against the run's wall-clock time, one line per method, a triangle at each frame in
which an edit began (each method reaches the edits at its own time); pt from scratch as points
(seconds for one image at N spp against its relMSE on the final state). Right: the same against
the frame number, the edits shaded (the same frames for every method); single-bounce methods
dashed against the single-bounce references. Uses Debian's python3-matplotlib.
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    title = None
    if "--title" in argv:
        i = argv.index("--title")
        if i + 1 >= len(argv):
            sys.exit("--title expects a value")
        title = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    if len(argv) != 2:
        sys.exit(__doc__.strip())
    out, path = argv
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for key in ("method", "frame", "wall_s", "edited", "relmse", "relmse_1b", "spp"):
        if rows and key not in rows[0]:
            sys.exit(f"{path}: missing column '{key}' (expected a compare-methods frames CSV)")
    methods = []
    for r in rows:
        if r["method"] not in methods:
            methods.append(r["method"])

    fig, (ax, ax_f) = plt.subplots(1, 2, figsize=(14, 5.5), sharey=True)
    edit_frames = set()
    for k, m in enumerate(methods):
        rs = [r for r in rows if r["method"] == m]
        colour = f"C{k % 10}"
        if m == "pt":
            t = [float(r["wall_s"]) for r in rs]
            e = [float(r["relmse"]) for r in rs]
            ax.plot(t, e, "o:", color="black", label="pt from scratch (" +
                    ", ".join(r["spp"] for r in rs) + " spp)")
            for ti, ei, r in zip(t, e, rs):
                ax.annotate(r["spp"], (ti, ei), textcoords="offset points", xytext=(4, 4),
                            fontsize=7)
            continue
        t = [float(r["wall_s"]) for r in rs]
        f = [int(r["frame"]) for r in rs]
        e = [float(r["relmse"]) for r in rs]
        ax.plot(t, e, color=colour, label=m, linewidth=1.2)
        ax_f.plot(f, e, color=colour, label=m, linewidth=1.2)
        starts = [i for i, r in enumerate(rs)
                  if r["edited"] == "1" and (i == 0 or rs[i - 1]["edited"] != "1")]
        ax.plot([t[i] for i in starts], [e[i] for i in starts], "v", color=colour, markersize=6)
        edit_frames.update(f[i] for i, r in enumerate(rs) if r["edited"] == "1")
        if rs[0]["relmse_1b"]:
            e1 = [float(r["relmse_1b"]) for r in rs]
            ax_f.plot(f, e1, "--", color=colour, label=m + " vs 1-bounce pt", linewidth=1.0)
    for fr in sorted(edit_frames):
        ax_f.axvspan(fr - 0.5, fr + 0.5, color="0.85", linewidth=0)
    ax.set_xlabel("wall-clock time (s); ▼ an edit begins")
    ax_f.set_xlabel("frame (edits shaded)")
    ax.set_ylabel("indirect relMSE against pt")
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    ax_f.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    ax_f.legend(fontsize=7, loc="upper right")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    tmp = os.path.join(os.path.dirname(os.path.abspath(out)), "." + os.path.basename(out) + ".tmp.png")
    fig.savefig(tmp, dpi=100)
    os.replace(tmp, out)  # atomic


if __name__ == "__main__":
    main(sys.argv[1:])
