#!/usr/bin/python3
"""check_convergence.py STATIC.csv SELECTIVE.csv FULL.csv MAX_RELMSE MAX_FRAMES

Checks three `afterglow converge` runs of the Cornell scene against the pm reference:
1. the static scene settles below MAX_RELMSE (indirect relMSE, the bias of coarse AIMs/IIMs);
2. after the last edit of cornell_move_cube.lua the selective run is back within 10% of its
   settled error within MAX_FRAMES frames;
3. from the first edit, the selective method gets there with less work (photons re-traced + texels gathered, counted,
   not timed) than --baseline full, which redoes everything every frame.
Prints the figures; exit 1 if a check fails.
"""
import csv
import sys


def rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def settled(r):
    tail = max(3, len(r) // 10)
    return sum(float(x["relmse"]) for x in r[-tail:]) / tail


def back_within(r, level):
    """(frames after the last edit until the error stays within 10% of `level`, work done from
    the first edit until then)."""
    edits = [i for i, x in enumerate(r) if x["edited"] == "1"]
    last = edits[-1] if edits else 0
    start = edits[0] if edits else 0
    first = None
    for i in range(len(r) - 1, last - 1, -1):
        if float(r[i]["relmse"]) > 1.1 * level:
            break
        first = i
    if first is None:
        return None, None
    work = sum(int(x["photons_retraced"]) + int(x["iim_texels"]) for x in r[start : first + 1])
    return first - last, work


def main(a):
    if len(a) != 5:
        print(__doc__.strip())
        return 2
    static, selective, full = rows(a[0]), rows(a[1]), rows(a[2])
    max_relmse, max_frames = float(a[3]), int(a[4])
    ok = True
    s = settled(static)
    print(f"static Cornell: settled indirect relMSE {s:.4f} (bound {max_relmse})")
    ok &= s < max_relmse
    level = settled(selective)
    frames_sel, work_sel = back_within(selective, level)
    frames_full, work_full = back_within(full, level)
    print(f"moving cube: settled relMSE {level:.4f}; back within 10%: selective after {frames_sel} frames "
          f"({work_sel} photons + texels of work), full after {frames_full} frames ({work_full})")
    ok &= frames_sel is not None and frames_sel <= max_frames
    ok &= frames_full is None or (work_sel is not None and work_sel < work_full)
    print("ok" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
