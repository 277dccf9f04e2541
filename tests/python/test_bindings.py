"""The Python bindings (tools/python): arrays, scene edits seen by the pipeline, errors with the
command line's messages, and the same image as `afterglow render`."""
import os
import threading
import time

import numpy as np
import pytest

import afterglow
from conftest import SOURCE_DIR, run

CORNELL = os.path.join(SOURCE_DIR, "scenes", "cornell.json")


def test_image_round_trip(tmp_path):
    rng = np.random.default_rng(7)
    image = rng.random((5, 7, 3), dtype=np.float32) * 4.0
    path = str(tmp_path / "x.exr")
    afterglow.write_image(image, path)
    back = afterglow.read_image(path)
    assert back.dtype == np.float32 and back.shape == (5, 7, 3)
    assert np.array_equal(back, image)  # EXR holds float32
    # Row-major, top row first: a pixel keeps its place.
    assert back[4, 6].tolist() == image[4, 6].tolist()


def test_metrics():
    a = np.full((16, 16, 3), 0.5, np.float32)
    b = a.copy()
    m = afterglow.compare(a, b)
    assert m["rmse"] == 0.0 and m["relmse"] == 0.0 and m["ssim"] == pytest.approx(1.0)
    b[0, 0] = [1.5, 0.5, 0.5]
    m = afterglow.compare(b, a)
    # relMSE = mean((x-y)^2 / (y^2 + 0.01)) over pixels and channels.
    assert m["relmse"] == pytest.approx(1.0 / (0.25 + 0.01) / (16 * 16 * 3), rel=1e-6)
    assert m["rmse"] == pytest.approx(np.sqrt(1.0 / (16 * 16 * 3)), rel=1e-6)
    heat = afterglow.error_heatmap(b, a, 1.0)
    assert heat.shape == (16, 16, 3)
    with pytest.raises(ValueError, match="shape"):
        afterglow.compare(np.zeros((4, 4, 2), np.float32), np.zeros((4, 4, 2), np.float32))


def test_pipeline_images_and_counters(cornell):
    p = afterglow.Pipeline(cornell, size=(40, 30), threads=1)
    counters = p.run(3)
    assert counters["frame"] == p.counters["frame"]
    assert counters["photons_verified"] > 0 and counters["frame_ms"] > 0
    images = p.images()
    assert set(images) == {"full", "direct", "indirect", "caustics", "specular", "volume"}
    for image in images.values():
        assert image.dtype == np.float32 and image.shape == (30, 40, 3)
    # The terms add up to the frame (eq. 13.2).
    total = sum(images[t] for t in afterglow.frame_terms)
    assert np.allclose(total, images["full"], rtol=1e-4, atol=1e-4)
    assert np.array_equal(p.image("indirect"), images["indirect"])
    assert images["direct"].max() > 0 and images["indirect"].max() > 0


def test_edit_seen_by_pipeline(cornell):
    cube = cornell.object("cube")
    p = afterglow.Pipeline(cornell, size=(32, 32), threads=1)
    p.run(4)
    before = p.image()
    version = cornell.version
    x, y, z = cube.position
    cube.translate((60.0, 0.0, 0.0))
    assert cube.position == pytest.approx((x + 60.0, y, z))
    assert cornell.version > version
    counters = p.run(1)
    assert counters["groups_invalidated_by_query"] > 0  # the move invalidated photon groups
    assert not np.array_equal(p.image(), before)
    # Lights and materials too.
    light = cornell.light("ceiling")
    light.set_enabled(False)
    p.run(2)
    assert p.image("direct").max() == 0.0  # the only light is off
    light.set_enabled(True)
    cube.set_albedo((0.2, 0.3, 0.4))
    assert cube.albedo == pytest.approx((0.2, 0.3, 0.4))
    cornell.set_camera(fov_y=50.0)
    assert cornell.camera["fov_y"] == pytest.approx(50.0)
    p.run(1)


def test_scene_from_dict_and_settings():
    scene = afterglow.Scene.from_dict({
        "camera": {"eye": [0, 1, 3], "target": [0, 1, 0]},
        "materials": {"white": {"albedo": [0.7, 0.7, 0.7]}},
        "lights": [{"name": "lamp", "type": "point", "position": [0, 1.8, 0],
                    "intensity": [5, 5, 5]}],
        "objects": [{"name": "floor", "material": "white",
                     "shape": {"type": "quad", "size": [4, 4]}},
                    {"name": "box", "material": "white", "dynamic": True, "shape": {"type": "box", "size": [1, 1, 1]},
                     "transform": {"translate": [0, 0.5, 0]}}],
    }, path=os.path.join(SOURCE_DIR, "scenes", "from_dict.json"))
    assert scene.objects == ["floor", "box"] and scene.lights == ["lamp"]
    scene.apply_settings({"photons": {"groups": 16}, "seed": 5})
    assert scene.settings["photons"]["groups"] == 16 and scene.settings["seed"] == 5
    copy = scene.copy()
    copy.object("box").translate((1, 0, 0))
    assert scene.object("box").position == pytest.approx((0, 0.5, 0))
    p = afterglow.Pipeline(scene, size=(16, 16), threads=1)
    p.run(2)
    assert p.image().max() > 0


def cli_error(afterglow_bin, *args):
    r = run([afterglow_bin, *args])
    assert r.returncode != 0
    prefix = "afterglow: error: "
    line = [l for l in r.stderr.splitlines() if l.startswith(prefix)]
    assert line, r.stderr
    return line[0][len(prefix):]


def test_errors_carry_the_cli_messages(afterglow_bin, tmp_path):
    with pytest.raises(afterglow.InputError) as e:
        afterglow.Scene.load("scenes/no_such_scene.json")
    assert str(e.value) == cli_error(afterglow_bin, "info", "scenes/no_such_scene.json")
    assert isinstance(e.value, ValueError)

    bad = tmp_path / "bad.json"
    bad.write_text('{"camera": {"eye": [0, 0, 1], "target": [0, 0, 0]}, "materials": {"m": {}}, '
                   '"lights": [], "objects": [{"name": "q", "material": "m", "shape": '
                   '{"type": "quad", "size": [1, -1]}}]}')
    with pytest.raises(afterglow.InputError) as e:
        afterglow.Scene.load(str(bad))
    assert str(e.value) == cli_error(afterglow_bin, "info", str(bad))
    assert "/objects/0/shape/size" in str(e.value)


def test_refused_pipeline_leaves_the_scene_settings_as_they_were(cornell):
    """Pipeline(scene, settings=...) applies the settings to the scene before the pipeline is
    built; when the pipeline refuses them (here rc.gather gl with rc.source direct), the scene
    gets its own settings back (fails if the bad settings stay on the scene)."""
    before = cornell.settings
    bad = {"indirect": {"method": "irradiance_cache"}, "rc": {"gather": "gl", "source": "direct"}}
    with pytest.raises(afterglow.InputError, match="rc.source"):
        afterglow.Pipeline(cornell, size=(8, 8), settings=bad)
    assert cornell.settings == before
    with pytest.raises(ValueError, match="mode"):
        afterglow.Pipeline(cornell, size=(8, 8), mode="fastest", settings={"seed": 99})
    assert cornell.settings == before
    # The scene still builds a pipeline, and the good settings of one that is built stay.
    afterglow.Pipeline(cornell, size=(8, 8), settings={"seed": 98}).run(1)
    assert cornell.settings["seed"] == 98


def test_errors_for_bad_edits_and_settings(cornell):
    with pytest.raises(afterglow.InputError, match=r"no object named 'nope' \(the scene has: "
                                                   r"floor, ceiling"):
        cornell.object("nope")
    with pytest.raises(afterglow.InputError, match="floor"):
        cornell.object("floor").translate((1, 0, 0))  # static
    with pytest.raises(afterglow.InputError, match="/photons/groups"):
        cornell.apply_settings({"photons": {"groups": "many"}})
    with pytest.raises(afterglow.InputError, match="/no_such_section"):
        afterglow.Pipeline(cornell, settings={"no_such_section": {}})
    with pytest.raises(afterglow.InputError):
        cornell.object("cube").translate((float("nan"), 0, 0))
    with pytest.raises(ValueError, match="component"):
        afterglow.Pipeline(cornell, size=(8, 8)).image("nope")
    with pytest.raises(ValueError, match="mode"):
        afterglow.Pipeline(cornell, size=(8, 8), mode="fastest")
    with pytest.raises(ValueError, match="region"):
        afterglow.render_reference(cornell, size=(8, 8), spp=1, region=(4, 4, 8, 8))


def test_same_image_as_cli(afterglow_bin, tmp_path):
    """`afterglow render` and Pipeline.run on the same scene and settings give the same frame,
    bit for bit: same library code, fixed per-frame counts (no frame-time target), QMC and fixed
    seeds, results independent of the thread count."""
    out = str(tmp_path / "cli.exr")
    r = run([afterglow_bin, "render", CORNELL, "-o", out, "--frames", "5", "--size", "48x36",
             "--set", "photons.groups=48", "--threads", "2", "-q", "--aov"])
    assert r.returncode == 0, r.stderr
    scene = afterglow.Scene.load(CORNELL)
    p = afterglow.Pipeline(scene, size=(48, 36), threads=1, settings={"photons": {"groups": 48}})
    p.run(5)
    assert np.array_equal(p.image(), afterglow.read_image(out))
    assert np.array_equal(p.image("indirect"),
                          afterglow.read_image(str(tmp_path / "cli.indirect.exr")))


def test_reference_tiles_merge_exactly(cornell):
    kw = dict(method="pt", spp=2, threads=1, size=(20, 14))
    whole = afterglow.render_reference(cornell, **kw)
    assert whole["spp"] == 2 and whole["full"].shape == (14, 20, 3)
    parts = [(r, afterglow.render_reference(cornell, region=r, **kw))
             for r in afterglow.tiles(20, 14, 8)]
    merged = afterglow.merge_tiles(parts, 20, 14)
    for c in afterglow.components:
        assert np.array_equal(merged[c], whole[c]), c
    with pytest.raises(ValueError, match="covered"):
        afterglow.merge_tiles(parts[1:], 20, 14)


def test_reference_same_as_cli(afterglow_bin, cornell, tmp_path):
    out = str(tmp_path / "ref.exr")
    r = run([afterglow_bin, "reference", CORNELL, "--method", "pt", "--spp", "2", "--size",
             "16x12", "--threads", "1", "-o", out, "-q"])
    assert r.returncode == 0, r.stderr
    ours = afterglow.render_reference(cornell, method="pt", spp=2, size=(16, 12), threads=2)
    assert np.array_equal(ours["full"], afterglow.read_image(out))


def test_convergence_study(cornell):
    reference = afterglow.render_reference(cornell, method="pt", spp=2, size=(24, 24), threads=1)
    seen = []
    result = afterglow.converge(cornell, script="", frames=6, size=(24, 24), threads=1,
                                reference=reference["indirect"],
                                progress=lambda done, total: seen.append((done, total)))
    table = result["table"]
    assert len(table["frame"]) == 6 and list(table["frame"]) == list(range(6))
    assert (np.diff(table["wall_s"]) > 0).all()
    assert (table["relmse"] > 0).all()
    assert result["csv"].splitlines()[0].startswith("method,frame,wall_s")
    assert len(result["csv"].splitlines()) == 7
    assert seen[-1] == (6, 6)
    assert result["settle"]["last_edit"] == 0
    with pytest.raises(ValueError, match="reference"):
        afterglow.converge(cornell, script="", frames=2, size=(24, 24),
                           reference=reference["indirect"][:10])


def test_frames_release_the_gil_and_block_edits(cornell):
    """The other thread runs Python while frames run (the GIL is released) and its edits are
    refused while the pipeline holds the scene. A refused edit proves both: it can only happen
    inside a frame, and only if the GIL was released there. Frames run until three edits were
    refused, not for a fixed number of frames: on a loaded machine the other thread may not be
    scheduled at all during a few short frames (the test counted its ticks during 12 frames and
    wanted 3)."""
    p = afterglow.Pipeline(cornell, size=(32, 32), threads=1)
    p.run(1)
    refused = []
    stop = threading.Event()

    def other_thread():
        while not stop.is_set():
            try:
                cornell.object("cube").translate((1.0, 0.0, 0.0))
            except RuntimeError as e:
                refused.append(str(e))
            time.sleep(0.001)

    t = threading.Thread(target=other_thread)
    t.start()
    # A hang guard, not a measurement (scaled for the sanitizers' build, tests/CMakeLists.txt).
    give_up = time.monotonic() + 60.0 * float(os.environ.get("AG_TEST_TIME_SCALE", "1"))
    frames = 0
    while len(refused) < 3 and time.monotonic() < give_up:
        p.run(1)
        frames += 1
    stop.set()
    t.join()
    assert len(refused) >= 3, (len(refused), frames)
    assert all("being rendered" in r for r in refused), refused[0]
