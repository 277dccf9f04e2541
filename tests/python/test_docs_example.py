"""The example of docs/python.md runs as written and writes its plot."""
import os
import re
import subprocess
import sys

from conftest import SOURCE_DIR


def example_code():
    with open(os.path.join(SOURCE_DIR, "docs", "python.md")) as f:
        text = f.read()
    section = text[text.index("## Example"):]
    match = re.search(r"```python\n(.*?)```", section, re.S)
    assert match, "docs/python.md: no python block under '## Example'"
    return match.group(1)


def test_docs_example_runs_as_written():
    plot = os.path.join(SOURCE_DIR, "out", "cube_loop.png")
    if os.path.exists(plot):
        os.remove(plot)
    r = subprocess.run([sys.executable, "-c", example_code()], cwd=SOURCE_DIR,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "wrote out/cube_loop.png" in r.stdout
    assert os.path.getsize(plot) > 10000
    # The jump invalidates photon groups and the error returns: the printed lines show frames
    # 0, 30, 60 and 90.
    assert len(re.findall(r"^frame \d+: ", r.stdout, re.M)) == 4
