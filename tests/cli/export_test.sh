#!/usr/bin/env bash
# export_test.sh AFTERGLOW SCENE: export writes an OBJ + MTL whose geometry matches `info`.
set -euo pipefail
bin="$1"; scene="$2"
d=$(mktemp -d); trap 'rm -rf "$d"' EXIT
"$bin" export "$scene" -o "$d/scene.obj"
test -s "$d/scene.obj" && test -s "$d/scene.mtl"
grep -q '^mtllib scene.mtl' "$d/scene.obj"
grep -q '^# point light' "$d/scene.obj"
grep -q '^Kd ' "$d/scene.mtl"
grep -q '^Ni 1.5' "$d/scene.mtl"
faces=$(grep -c '^f ' "$d/scene.obj")
tris=$("$bin" info "$scene" | awk '/^triangles/ {print $2}')
[ "$faces" -eq "$tris" ] || { echo "export has $faces faces, info says $tris triangles" >&2; exit 1; }
# Every face index refers to an existing vertex.
verts=$(grep -c '^v ' "$d/scene.obj")
awk -v n="$verts" '/^f / { for (i = 2; i <= 4; ++i) if ($i < 1 || $i > n) { print "bad index " $i; exit 1 } }' "$d/scene.obj"
ls -a "$d" | grep -q tmp && { echo "temporary file left behind" >&2; exit 1; }
echo "export ok: $faces faces, $verts vertices"
