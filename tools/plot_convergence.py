#!/usr/bin/python3
"""Plot error against wall-clock time from one or more `afterglow converge` CSV files.

usage: tools/plot_convergence.py OUT.png RUN.csv [RUN.csv ...] [--title TEXT]

Each CSV becomes one line (labelled by its `method` column, else its file name, and the seconds
from the last edit until the error stays within 10% of its settled value, marked by a dot);
vertical lines mark the frames at which the script edited the scene (the `edited` column).
Uses Debian's python3-matplotlib (the system interpreter, hence the shebang).
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{path}: no rows")
    for key in ("wall_s", "relmse"):
        if key not in rows[0]:
            sys.exit(f"{path}: missing column '{key}' (expected an afterglow converge CSV)")
    return rows


def settle(rows, e):
    """(frame, seconds after the last edit) from which the error stays within 10% of the mean of
    the last tenth of the frames (at least 3), or None: the rule of `afterglow converge`."""
    tail = min(len(e), max(3, len(e) // 10))
    level = sum(e[-tail:]) / tail
    edits = [i for i, r in enumerate(rows) if r.get("edited") == "1"]
    last = edits[-1] if edits else 0
    within = None
    for i in range(len(e) - 1, last - 1, -1):
        if abs(e[i] - level) > 0.1 * level:
            break
        within = i
    if within is None:
        return None
    return within, float(rows[within]["wall_s"]) - float(rows[last]["wall_s"])


def main(argv):
    title = None
    if "--title" in argv:
        i = argv.index("--title")
        title = argv[i + 1]
        del argv[i : i + 2]
    if len(argv) < 2 or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    out, runs = argv[0], argv[1:]
    fig, ax = plt.subplots(figsize=(7, 4.2), dpi=110)
    for path in runs:
        rows = read(path)
        label = rows[0].get("method") or os.path.basename(path)
        t = [float(r["wall_s"]) for r in rows]
        e = [float(r["relmse"]) for r in rows]
        s = settle(rows, e)
        label += f" (settled {s[1]:.2f} s after the edit)" if s else " (did not settle)"
        line, = ax.plot(t, e, label=label, linewidth=1.4)
        if s:
            ax.plot([t[s[0]]], [e[s[0]]], "o", color=line.get_color(), markersize=5)
        for r in rows:
            if r.get("edited") == "1":
                ax.axvline(float(r["wall_s"]), color=line.get_color(), alpha=0.12, linewidth=0.8)
    ax.set_yscale("log")
    ax.set_xlabel("wall-clock time (s)")
    ax.set_ylabel("relMSE against the reference")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    if title:
        ax.set_title(title)
    fig.tight_layout()
    tmp = os.path.join(os.path.dirname(os.path.abspath(out)), "." + os.path.basename(out) + ".tmp.png")
    fig.savefig(tmp)
    os.replace(tmp, out)  # atomic
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
