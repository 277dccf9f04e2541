#!/usr/bin/python3
"""Plot error against wall-clock time from one or more `afterglow converge` CSV files.

usage: tools/plot_convergence.py OUT.png RUN.csv [RUN.csv ...] [--title TEXT] [--settled X]
                                  [--since-edit]

Each CSV becomes one line (labelled by its `method` column, else its file name, and the seconds
from the start of the last edit's frame until the error stays within 10% of its settled value,
marked by a dot); vertical lines mark the frames at which the script edited the scene (the
`edited` column). The settled value is each run's own (the mean of its last tenth of frames)
unless --settled gives one for every run (`afterglow bench settle`'s: the error of the converged
final state; its CSV's `settled_relmse`), drawn as a dotted line. --since-edit puts the start of
the last edit's frame at 0 and shows the seconds around it, up to twice the latest settle, so a
slow baseline does not squeeze the others into the left edge. Uses Debian's python3-matplotlib
(the system interpreter, hence the shebang).
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


def settle(rows, e, level=None):
    """(frame, seconds from the start of the last edit's frame) from which the error stays within
    10% of `level` (default: the mean of the last tenth of the frames, at least 3, the rule of
    `afterglow converge` without --prime), or None."""
    if level is None:
        tail = min(len(e), max(3, len(e) // 10))
        level = sum(e[-tail:]) / tail
    last = last_edit(rows)
    within = None
    for i in range(len(e) - 1, last - 1, -1):
        if abs(e[i] - level) > 0.1 * level:
            break
        within = i
    if within is None:
        return None
    return within, float(rows[within]["wall_s"]) - edit_start(rows)


def last_edit(rows):
    edits = [i for i, r in enumerate(rows) if r.get("edited") == "1"]
    return edits[-1] if edits else 0


def edit_start(rows):
    """The wall time at which the last edit's frame started (the end of the frame before it)."""
    last = last_edit(rows)
    return float(rows[last - 1]["wall_s"]) if last > 0 else 0.0


def option(argv, name):
    if name not in argv:
        return None
    i = argv.index(name)
    if i + 1 >= len(argv):
        sys.exit(f"plot_convergence.py: {name} expects a value")
    value = argv[i + 1]
    del argv[i : i + 2]
    return value


def main(argv):
    title = option(argv, "--title")
    settled = option(argv, "--settled")
    if settled is not None:
        try:
            settled = float(settled)
        except ValueError:
            sys.exit(f"plot_convergence.py: --settled expects a number, got '{settled}'")
        if not settled > 0:
            sys.exit(f"plot_convergence.py: --settled expects a positive number, got {settled}")
    since_edit = "--since-edit" in argv
    if since_edit:
        argv.remove("--since-edit")
    if len(argv) < 2 or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if argv and argv[0] in ("-h", "--help") else 2
    out, runs = argv[0], argv[1:]
    fig, ax = plt.subplots(figsize=(7.5, 4.4), dpi=110)
    latest = 0.0
    for path in runs:
        rows = read(path)
        label = rows[0].get("method") or os.path.basename(path)
        origin = edit_start(rows) if since_edit else 0.0
        t = [float(r["wall_s"]) - origin for r in rows]
        e = [float(r["relmse"]) for r in rows]
        s = settle(rows, e, settled)
        if s:
            latest = max(latest, s[1])
            n = s[0] - last_edit(rows)
            label += f" (settled {s[1]:.3f} s, {n} frame{'' if n == 1 else 's'} after the edit)"
        else:
            label += " (did not settle)"
        line, = ax.plot(t, e, label=label, linewidth=1.4, marker="." if since_edit else None,
                        markersize=3)
        if s:
            ax.plot([t[s[0]]], [e[s[0]]], "o", color=line.get_color(), markersize=6)
        for r in rows:
            if r.get("edited") == "1":
                ax.axvline(float(r["wall_s"]) - origin, color=line.get_color(), alpha=0.12,
                           linewidth=0.8)
    if settled is not None:
        ax.axhline(settled, color="black", linestyle=":", linewidth=1.0,
                   label=f"settled {settled:.4g} (±10%)")
        ax.axhspan(0.9 * settled, 1.1 * settled, color="black", alpha=0.06)
    if since_edit:
        span = max(2.0 * latest, 0.3)
        ax.set_xlim(-0.25 * span, span)
        ax.set_xlabel("wall-clock time from the start of the edit's frame (s)")
    else:
        ax.set_xlabel("wall-clock time (s)")
    ax.set_yscale("log")
    ax.set_ylabel("relMSE against the reference")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    if title:
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    tmp = os.path.join(os.path.dirname(os.path.abspath(out)), "." + os.path.basename(out) + ".tmp.png")
    fig.savefig(tmp)
    os.replace(tmp, out)  # atomic
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
