#!/usr/bin/python3
"""check_settle.py SELECTIVE.csv FULL_BUDGET.csv

Counts frames, not time: from the last edit (the `edited` column) until the indirect error stays
within 10% of its settled value (the mean of the last tenth of the frames, at least 3), each run
against its own settled value, as `afterglow converge` and `bench settle` count them. Checks that
the selective run settles, and in no more frames than the full-budget run at the same --frame-ms.
Prints the figures; exit 1 if the check fails.
"""
import csv
import sys


def settle_frames(path):
    with open(path, newline="") as f:
        r = list(csv.DictReader(f))
    e = [float(x["relmse"]) for x in r]
    tail = min(len(e), max(3, len(e) // 10))
    level = sum(e[-tail:]) / tail
    edits = [i for i, x in enumerate(r) if x["edited"] == "1"]
    last = edits[-1] if edits else 0
    within = None
    for i in range(len(e) - 1, last - 1, -1):
        if abs(e[i] - level) > 0.1 * level:
            break
        within = i
    return level, last, None if within is None else within - last


def main(a):
    if len(a) != 2:
        print(__doc__.strip())
        return 2
    level_s, edit_s, sel = settle_frames(a[0])
    level_b, edit_b, bud = settle_frames(a[1])
    print(f"cube jump at frame {edit_s}: selective settles (relMSE {level_s:.4f}) after {sel} frames, "
          f"full-budget (relMSE {level_b:.4f}) after {bud} frames")
    ok = sel is not None and (bud is None or sel <= bud)
    print("ok" if ok else "FAILED: selective should settle in no more frames than full-budget")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
