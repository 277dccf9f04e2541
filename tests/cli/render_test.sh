#!/usr/bin/env bash
# render_test.sh AFTERGLOW: a small headless render writes EXR + PNG and the four terms; exit 77
# (skipped) if no GL context can be made on this machine.
set -uo pipefail
bin="$1"
d=$(mktemp -d); trap 'rm -rf "$d"' EXIT
"$bin" glinfo >/dev/null 2>&1 || { echo "no OSMesa context: skipped"; exit 77; }
"$bin" render scenes/cornell.json -o "$d/c.exr" --frames 4 --size 64x48 --aov -q || exit 1
for f in c.exr c.png c.direct.exr c.indirect.exr c.specular.exr c.caustics.exr c.direct.png; do
  [ -s "$d/$f" ] || { echo "missing $f" >&2; exit 1; }
done
ls -a "$d" | grep -q tmp && { echo "temporary file left behind" >&2; exit 1; }
echo "render ok"
