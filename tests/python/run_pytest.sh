#!/usr/bin/env bash
# run_pytest.sh PYTHON AFTERGLOW PYTHONPATH TEST.py...: the pytest tests of the Python bindings;
# exit 77 (skipped) if no GL context can be made on this machine.
set -uo pipefail
python="$1" bin="$2"
export PYTHONPATH="$3" AFTERGLOW="$2"
shift 3
"$bin" glinfo >/dev/null 2>&1 || { echo "no OSMesa context: skipped"; exit 77; }
exec "$python" -m pytest -q -p no:cacheprovider "$@"
