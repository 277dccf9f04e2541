"""tools/plot_convergence.py: the settle rule it labels lines with, and its options."""
import csv
import importlib.util
import os

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SPEC = importlib.util.spec_from_file_location(
    "plot_convergence", os.path.join(HERE, "..", "..", "tools", "plot_convergence.py"))
plot = importlib.util.module_from_spec(SPEC)
SPEC.loader.exec_module(plot)


def rows_of(errors, edit):
    """Frames of 0.1 s each ending at 0.1, 0.2, ...; the script edits at frame `edit`."""
    return [{"wall_s": f"{0.1 * (i + 1):.3f}", "relmse": str(e), "edited": "1" if i == edit else "0",
             "method": "m"} for i, e in enumerate(errors)]


def test_settle_counts_from_the_start_of_the_edit_frame_against_a_given_level():
    e = [1.0, 1.0, 1.0, 0.5, 0.2, 0.105, 0.1, 0.1, 0.1, 0.1]
    rows = rows_of(e, 3)
    frame, seconds = plot.settle(rows, e, 0.1)
    assert frame == 5  # 0.105 is within 10% of 0.1, 0.2 is not
    assert seconds == pytest.approx(0.6 - 0.3)  # the end of frame 5 from the end of frame 2


def test_settle_waits_until_the_error_stays_within_the_band():
    e = [1.0, 1.0, 0.1, 0.1, 0.2, 0.1, 0.1]
    rows = rows_of(e, 1)
    assert plot.settle(rows, e, 0.1)[0] == 5
    assert plot.settle(rows, [1.0] * 7, 0.1) is None


def test_without_a_level_each_run_settles_against_its_last_tenth():
    e = [1.0, 1.0, 0.5, 0.3] + [0.2] * 6
    assert plot.settle(rows_of(e, 1), e)[0] == 4


def test_writes_the_plot_and_refuses_a_bad_settled_value(tmp_path):
    e = [1.0, 1.0, 0.5, 0.11, 0.1, 0.1]
    path = tmp_path / "run.csv"
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["method", "wall_s", "relmse", "edited"])
        w.writeheader()
        w.writerows(rows_of(e, 1))
    out = tmp_path / "plot.png"
    assert plot.main([str(out), str(path), "--settled", "0.1", "--since-edit"]) == 0
    assert out.stat().st_size > 1000
    assert not list(tmp_path.glob(".*tmp*"))  # written atomically, nothing left beside it
    for bad in (["--settled", "-1"], ["--settled", "x"], ["--settled"]):
        with pytest.raises(SystemExit):
            plot.main([str(out), str(path)] + bad)
