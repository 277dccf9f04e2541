#!/usr/bin/env bash
# install_test.sh BUILD_DIR PYTHON: `cmake --install` into BUILD_DIR/install-test/prefix, then
# configure, build and run tests/install against it with find_package(Afterglow), and import the
# installed Python module. Exit 77 (skipped) where no GL context can be made.
set -euo pipefail
build="$1" python="$2"
src="$(cd "$(dirname "$0")/../.." && pwd)"
work="$build/install-test"
rm -rf "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src/tests/install" -B "$work/build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/build" -j2 >/dev/null
rc=0
"$work/build/install_example" "$src/scenes/cornell.json" || rc=$?
[ $rc -eq 0 ] || exit $rc
# The Python module installed beside the library, loading it through its RPATH.
where=$(cd / && PYTHONPATH="$work/prefix/lib/python3/dist-packages" "$python" -c \
  'import afterglow, afterglow.sweep; print(afterglow.__file__)')
case "$where" in
  "$work/prefix/"*) echo "python module: $where" ;;
  *) echo "imported afterglow from $where, not from the install prefix" >&2; exit 1 ;;
esac
