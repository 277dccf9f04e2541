#!/usr/bin/env bash
# reference_frames_test.sh AFTERGLOW WORK: `converge --reference-frames F1,F2` (issue #18, the
# ghosting check of temporal caching) on Cube in a Box, 6 frames at 24², cheap pm references.
# Holds: a frame outside the run is refused (exit 2, the flag named) before any reference is
# rendered; the last frame's own reference is the final state's (same cache file, same relMSE as
# the CSV's last row); frame 2's is another state (the cube moved: another file, and the final
# reference scores frame 2 differently from its own). Exit 77 (skipped) without a GL context.
set -uo pipefail
bin="$1"; work="$2/reference_frames"
"$bin" glinfo >/dev/null 2>&1 || { echo "no GL context: skipped"; exit 77; }
rm -rf "$work"; mkdir -p "$work"
common=(scenes/cube_in_a_box.json -n 6 --size 24x24 --ref-spp 4 --ref-photons 20000
        --reference-bounces 1 --plot '' --cache "$work/cache" -q)
out=$("$bin" converge "${common[@]}" --reference-frames 2,6 2>&1); rc=$?
[ $rc -eq 2 ] && grep -q -- '--reference-frames: "6" is not a frame in 0..5' <<<"$out" ||
  { echo "FAIL: frame 6 of 6 not refused (exit $rc): $out"; exit 1; }
[ -z "$(ls -A "$work/cache" 2>/dev/null)" ] || { echo "FAIL: a reference was rendered first"; exit 1; }
out=$("$bin" converge "${common[@]}" --csv "$work/run.csv" --reference-frames 2,5 2>&1) ||
  { echo "FAIL: converge: $out"; exit 1; }
echo "$out"
python3 - "$work/run.csv" <<PY || exit 1
import csv, re, sys
out = """$out"""
final = re.search(r"settled relMSE [0-9.]+ \(([^)]*)\)", out).group(1)
at = {int(f): (float(e), p) for f, e, p in
      re.findall(r"frame (\d+): relMSE ([0-9.]+) against its own state \(([^)]*)\)", out)}
rows = list(csv.DictReader(open(sys.argv[1])))
last = float(rows[-1]["relmse"])
ok = sorted(at) == [2, 5]
ok &= at[5][1] == final and abs(at[5][0] - last) < 1e-5
ok &= at[2][1] != final and abs(at[2][0] - float(rows[2]["relmse"])) > 1e-6
print("frame 2", at[2], "frame 5", at[5], "csv frame 2", rows[2]["relmse"], "last", last)
sys.exit(0 if ok else 1)
PY
