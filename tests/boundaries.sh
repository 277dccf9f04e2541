#!/usr/bin/env bash
# The folder boundaries (DESIGN.md, docs/architecture.md): cpu/ never includes GL, gpu/ never
# includes Embree or FLANN, the base layer of shared/ (all but shared/pipeline/) includes neither
# side, and no pipeline, IIM or frame-loop code sits in the commands (tools/afterglow/).
set -uo pipefail
cd "${1:-.}"
status=0
check() {  # check DESCRIPTION PATTERN FILES...
  local what="$1" pattern="$2"
  shift 2
  local hits
  hits=$(grep -nE "$pattern" "$@" 2>/dev/null)
  if [ -n "$hits" ]; then
    echo "boundary broken: $what" >&2
    echo "$hits" >&2
    status=1
  fi
}
mapfile -t cpu < <(git ls-files 'cpu/*.h' 'cpu/*.cpp')
mapfile -t gpu < <(git ls-files 'gpu/*.h' 'gpu/*.cpp')
mapfile -t base < <(git ls-files 'shared/*.h' 'shared/*.cpp' | grep -v '^shared/pipeline/')
mapfile -t commands < <(git ls-files 'tools/afterglow/*.h' 'tools/afterglow/*.cpp')
check "cpu/ includes GL" '#include [<"](GL/|EGL/|GLFW/|gpu/)' "${cpu[@]}"
check "gpu/ includes Embree or FLANN" '#include [<"](embree|flann|cpu/)' "${gpu[@]}"
check "shared/ includes cpu/ or gpu/" '#include [<"](cpu|gpu)/' "${base[@]}"
check "tools/afterglow/ defines pipeline parts" \
  '^(class|struct) (Pipeline|Iim|FrameLoop|IndirectMethod)\b|Pipeline::frame\(\)\s*\{' "${commands[@]}"
if [ $status -eq 0 ]; then
  echo "boundaries hold: ${#cpu[@]} cpu/, ${#gpu[@]} gpu/, ${#base[@]} shared/ and ${#commands[@]} tools/afterglow/ files"
fi
exit $status
