#!/usr/bin/env bash
# mcguire_test.sh AFTERGLOW WORK: issue #14's acceptance at a small size. McGuire's
# CornellBox-Original, lit by its own emissive quad (a mesh light), rendered by the progressive
# pipeline and by the path tracer must agree to relMSE <= 0.02. Exit 77 (skipped) without
# ../shared/external-scenes or a GL context.
set -uo pipefail
bin="$1"; work="$2"
[ -f ../shared/external-scenes/cornell-box/CornellBox-Original.obj ] ||
  { echo "../shared/external-scenes is absent: skipped"; exit 77; }
"$bin" glinfo >/dev/null 2>&1 || { echo "no GL context: skipped"; exit 77; }
mkdir -p "$work"
"$bin" render scenes/cornell_mcguire.json -o "$work/mcguire.exr" --size 64x64 -n 40 -q || exit 1
"$bin" reference scenes/cornell_mcguire.json --method pt -o "$work/mcguire_pt.exr" --size 64x64 \
  --spp 256 -q || exit 1
metrics=$("$bin" compare "$work/mcguire.exr" "$work/mcguire_pt.exr" --json) || exit 1
echo "$metrics"
relmse=$(echo "$metrics" | sed -n 's/.*"relmse":\([0-9.eE+-]*\).*/\1/p')
awk -v e="$relmse" 'BEGIN { if (e == "" || !(e <= 0.02)) { print "relMSE " e " > 0.02"; exit 1 } }'
