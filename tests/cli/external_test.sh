#!/usr/bin/env bash
# external_test.sh FILE CODE REGEX CMD...: expect.sh for a scene that wraps a mesh from
# ../shared/external-scenes (beside the repository, never in it). Where FILE is absent it exits 77,
# which CTest reports as skipped (SKIP_RETURN_CODE), never as passed or failed.
set -u
file="$1"; shift
if [ ! -f "$file" ]; then
  echo "external_test.sh: skipped: $file is absent (../shared/external-scenes is not beside the repository)"
  exit 77
fi
exec "$(dirname "$0")/expect.sh" "$@"
