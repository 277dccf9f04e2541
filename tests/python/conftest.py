"""pytest set-up for the Python bindings (tests/python/python.cmake runs these through CTest with
PYTHONPATH=BUILD/python and AFTERGLOW=the afterglow binary)."""
import os
import subprocess

import pytest

SOURCE_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


@pytest.fixture(scope="session")
def afterglow_bin():
    path = os.environ.get("AFTERGLOW")
    if not path or not os.path.isfile(path):
        pytest.skip("AFTERGLOW (the afterglow binary) not set")
    return path


@pytest.fixture(scope="session", autouse=True)
def gl_available():
    """The tests need a GL context for the pipeline; without one they are skipped (CTest maps
    the skip to its SKIP_RETURN_CODE through tests/python/run_pytest.sh)."""
    import afterglow
    try:
        scene = afterglow.Scene.load(os.path.join(SOURCE_DIR, "scenes", "cornell.json"))
        afterglow.Pipeline(scene, size=(8, 8))
    except RuntimeError as e:
        pytest.skip(f"no GL context: {e}")


@pytest.fixture
def cornell():
    import afterglow
    return afterglow.Scene.load(os.path.join(SOURCE_DIR, "scenes", "cornell.json"))


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, cwd=SOURCE_DIR, **kw)
