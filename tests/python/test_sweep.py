"""The Dask sweep (afterglow.sweep, tools/sweep): 2 scenes x 2 settings on a LocalCluster of 2
workers; the tiled references merge into exactly the single-process render; a failing task is
retried and reported, never dropped."""
import csv
import logging
import os

import numpy as np
import pytest

import afterglow
import afterglow.sweep as sweep
from conftest import SOURCE_DIR

SIZE = [24, 24]
FRAMES = 8


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None, silence_logs=logging.ERROR)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def spec(settings):
    return sweep.normalise_spec({
        "scenes": [{"path": os.path.join(SOURCE_DIR, "scenes", "cornell.json"),
                    "script": os.path.join(SOURCE_DIR, "scenes", "cornell_move_cube.lua")},
                   {"path": os.path.join(SOURCE_DIR, "scenes", "cornell_34.json"), "script": ""}],
        "settings": settings, "frames": FRAMES, "size": SIZE, "threads": 1, "retries": 1,
        "reference": {"method": "pt", "spp": 3, "tile": 10, "verify": True},
    })


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_sweep_two_scenes_two_settings(client, tmp_path):
    s = spec({"default": {}, "groups32": {"photons": {"groups": 32}}})
    rows = sweep.run(s, str(tmp_path), client=client)
    assert all(r["status"] == "finished" for r in rows), rows
    assert all(r["attempts"] == 1 for r in rows), rows  # counted on the workers
    kinds = [r["kind"] for r in rows]
    assert kinds.count("converge") == 4 and kinds.count("reference merge") == 2
    assert kinds.count("reference tile") == 2 * 9  # 24x24 in tiles of 10: 3 x 3

    # The merged reference equals a single-process render of the same samples, bit for bit.
    for scene_spec in s["scenes"]:
        scene = afterglow.Scene.load(scene_spec["path"])
        if scene_spec["script"]:
            scene.run_script(scene_spec["script"], FRAMES)
        whole = afterglow.render_reference(scene, method="pt", spp=3, size=tuple(SIZE),
                                           threads=2)
        for c in afterglow.components:
            stem = scene_spec["name"] + ("" if c == "full" else "." + c)
            merged = np.load(tmp_path / "references" / (stem + ".npy"))
            assert np.array_equal(merged, whole[c]), (scene_spec["name"], c)

    table = read_csv(tmp_path / "sweep.csv")
    assert len(table) == 4 * FRAMES
    runs = {(r["scene"], r["settings"]) for r in table}
    assert runs == {(a, b) for a in ("cornell", "cornell_34") for b in ("default", "groups32")}
    assert all(float(r["relmse"]) > 0 for r in table)
    # The move script edits the cube from its first frame on; the other scene has no script.
    assert any(r["edited"] == "1" for r in table if r["scene"] == "cornell" and r["frame"] != "0")
    assert not any(r["edited"] == "1" for r in table if r["scene"] == "cornell_34")
    assert len(os.listdir(tmp_path / "plots")) == 4


def test_sweep_reports_failed_tasks(client, tmp_path):
    s = spec({"broken": {"photons": {"groups": "many"}}})
    s["scenes"] = s["scenes"][1:]
    s["reference"]["verify"] = False
    rows = sweep.run(s, str(tmp_path), client=client, plots=False)
    failed = [r for r in rows if r["status"] != "finished"]
    assert len(failed) == 1 and failed[0]["kind"] == "converge"
    assert failed[0]["attempts"] == 2  # tried, then retried once (counted on the workers)
    assert "/photons/groups" in failed[0]["error"]
    summary = read_csv(tmp_path / "summary.csv")
    assert [r["status"] for r in summary if r["kind"] == "converge"] == ["error"]


def test_spec_errors(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"scenes": ["nope.json"]}')
    with pytest.raises(sweep.SpecError, match=r"bad.json: /scenes/0/path: no such file"):
        sweep.load_spec(str(bad))
    bad.write_text('{"scenes": [], "colour": 1}')
    with pytest.raises(sweep.SpecError, match="/colour: unknown key"):
        sweep.load_spec(str(bad))
