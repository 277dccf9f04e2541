#!/usr/bin/env python3
"""Robustness sweep (docs/robustness.md, "Renderer sweep"): extreme but valid scenes through every
renderer, as a user runs them. Each case is a scene file (and perhaps an edit script or a mesh)
written to a scratch folder; each run is one `afterglow` command on it (render with every
indirect method, converge, the pt and pm references, media). A run fails on a crash (a signal or
an exit code other than 0 and 1), on running past its time limit, on any NaN or infinite value in
any image it wrote (checked by `afterglow compare IMAGE IMAGE`, which refuses non-finite images),
on a missing image, and on an exit 1 where the case is expected to render (or an exit 0 where it
is expected to be refused). Standard library only; prints one line per run and a summary.

    tools/robustness_sweep.py [--afterglow build/afterglow] [--mode ci|methods|full] [-j 2]
                              [--only REGEX] [--every N] [--keep DIR] [--timeout S] [--list]

Exit 0 when every run passed, 1 when one failed, 77 when no GL context can be made.
"""
import argparse
import base64
import concurrent.futures
import copy
import json
import math
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SIZE = "16x16"
FRAMES = "3"

# --- scenes -----------------------------------------------------------------------------------


def quad(name, material, size, translate, axis=None, degrees=0.0, dynamic=False):
    t = {"translate": list(translate)}
    if axis is not None:
        t["rotate"] = {"axis": list(axis), "degrees": degrees}
    o = {"name": name, "material": material, "shape": {"type": "quad", "size": list(size)},
         "transform": t}
    if dynamic:
        o["dynamic"] = True
    return o


def room_walls(s=1.0, material="white", left="red", right="green", closed=False):
    """A Cornell-like room [0, s]^3 open towards -z (closed: a sixth wall facing +z)."""
    h = s / 2
    walls = [
        quad("floor", material, (s, s), (h, 0, h)),
        quad("ceiling", material, (s, s), (h, s, h), (1, 0, 0), 180),
        quad("back_wall", material, (s, s), (h, h, s), (1, 0, 0), -90),
        quad("left_wall", left, (s, s), (s, h, h), (0, 0, 1), 90),
        quad("right_wall", right, (s, s), (0, h, h), (0, 0, 1), -90),
    ]
    if closed:
        walls.append(quad("front_wall", material, (s, s), (h, h, 0), (1, 0, 0), 90))
    return walls


def cornell(s=1.0):
    """A 1-unit Cornell box with a dynamic cube, a dynamic glass sphere and a point light: the
    base every case changes. Small photon and caustic budgets keep each run to about a second."""
    return {
        "name": "robust",
        "units": "m",
        "camera": {"eye": [0.5, 0.5, -1.44], "target": [0.5, 0.5, 0], "fov_y": 39.3,
                   "resolution": [16, 16]},
        "materials": {
            "white": {"albedo": 0.75},
            "red": {"albedo": [0.63, 0.065, 0.05]},
            "green": {"albedo": [0.14, 0.45, 0.091]},
            "cube": {"albedo": 0.75},
            "glass": {"type": "glass", "ior": 1.5},
        },
        "lights": [{"name": "lamp", "type": "point", "position": [0.5, 0.946, 0.5],
                    "intensity": [1.3, 1.1, 0.8]}],
        "objects": room_walls(s) + [
            {"name": "cube", "material": "cube", "dynamic": True,
             "shape": {"type": "box", "size": [0.3, 0.3, 0.3]},
             "transform": {"rotate": {"axis": [0, 1, 0], "degrees": -17},
                           "translate": [0.33, 0.15, 0.3]}},
            {"name": "sphere", "material": "glass", "dynamic": True,
             "shape": {"type": "sphere", "radius": 0.16, "subdivisions": 2},
             "transform": {"translate": [0.66, 0.16, 0.63]}},
        ],
        "settings": {
            "photons": {"groups": 16, "photons_per_group": 8},
            "lightmap": {"texel_size": 0.2},
            "gather": {"texels_per_frame": 40, "plane_resolution": 8, "cpu_rays": 16},
            "caustics": {"photons": 500, "frames": 2},
            "specular": {"cube_map_size": 8},
            "direct": {"area_light_samples": 4, "map_size": 8, "accumulate_frames": 2},
            "frame": {"accumulate_frames": 2},
            "gpu_pm": {"paths": 100, "frames": 2},
            "vpl": {"map_size": 8, "photons_per_group": 1, "walk_paths": 16,
                    "updates_per_frame": 16},
            "rc": {"records_per_frame": 32, "phi_strata": 8, "theta_strata": 4},
            "threads": 2,
        },
    }


def with_all_materials(scene, **fields):
    for m in scene["materials"].values():
        if m.get("type", "diffuse") == "diffuse":
            m.update(fields)
    return scene


def furnace(albedo, material_type="diffuse", light="point"):
    """A closed box (six walls, camera inside) of one material: with albedo 1 nothing is ever
    absorbed, so only the bounce caps keep energy finite."""
    sc = cornell()
    m = {"albedo": albedo}
    if material_type != "diffuse":
        m["type"] = material_type
    sc["materials"] = {"wall": m, "red": m, "green": m}
    sc["objects"] = room_walls(1.0, "wall", "wall", "wall", closed=True)
    sc["camera"]["eye"] = [0.5, 0.5, 0.1]
    sc["camera"]["target"] = [0.5, 0.5, 1.0]
    if light == "quad":
        sc["lights"] = [quad_light(0.4, 0.999, 2.0)]
    return sc


def quad_light(x0, y, radiance, size=0.2, name="panel"):
    x1 = x0 + size
    return {"name": name, "type": "quad", "radiance": radiance,
            "corners": [[x0, y, x0], [x1, y, x0], [x1, y, x1], [x0, y, x1]]}


def moved(scene, offset):
    """The whole scene translated by offset (camera, lights, every object)."""
    sc = copy.deepcopy(scene)
    add = lambda p: [a + b for a, b in zip(p, offset)]  # noqa: E731
    sc["camera"]["eye"] = add(sc["camera"]["eye"])
    sc["camera"]["target"] = add(sc["camera"]["target"])
    for light in sc["lights"]:
        if "position" in light:
            light["position"] = add(light["position"])
        if "corners" in light:
            light["corners"] = [add(c) for c in light["corners"]]
    for o in sc["objects"]:
        o["transform"]["translate"] = add(o["transform"]["translate"])
    for m in sc.get("media", []):
        m["bounds"] = {k: add(v) for k, v in m["bounds"].items()}
    return sc


def scaled(scene, k):
    """The scene scaled by k about the origin: lengths by k, point intensities by k^2 (the same
    irradiance at the scaled distances), media coefficients by 1/k; radiance is unchanged."""
    sc = copy.deepcopy(scene)
    mul = lambda p: [a * k for a in p]  # noqa: E731
    sc["camera"]["eye"] = mul(sc["camera"]["eye"])
    sc["camera"]["target"] = mul(sc["camera"]["target"])
    for light in sc["lights"]:
        if "position" in light:
            light["position"] = mul(light["position"])
        if "corners" in light:
            light["corners"] = [mul(c) for c in light["corners"]]
        if "intensity" in light:
            i = light["intensity"]
            light["intensity"] = [a * k * k for a in i] if isinstance(i, list) else i * k * k
    for o in sc["objects"]:
        o["transform"]["translate"] = mul(o["transform"]["translate"])
        shape = o.get("shape", {})
        if "size" in shape:
            shape["size"] = mul(shape["size"])
        if "radius" in shape:
            shape["radius"] *= k
    for m in sc.get("media", []):
        m["bounds"] = {key: mul(v) for key, v in m["bounds"].items()}
        m["sigma_s"] /= k
        m["sigma_a"] /= k
    sc["settings"]["lightmap"]["texel_size"] *= k
    return sc


def edit(fn):
    """A case's scene: the base with fn applied."""
    sc = cornell()
    fn(sc)
    return sc


def set_path(d, path, value):
    keys = path.split(".")
    for k in keys[:-1]:
        d = d.setdefault(k, {})
    d[keys[-1]] = value


def settings(**kv):
    def fn(sc):
        for k, v in kv.items():
            set_path(sc["settings"], k.replace("__", "."), v)
    return fn


def obj(name):
    return lambda sc: next(o for o in sc["objects"] if o["name"] == name)


def fog(sigma_s, sigma_a, bounds=((0.0, 0.0, 0.0), (1.0, 1.0, 1.0))):
    def fn(sc):
        sc["media"] = [{"bounds": {"min": list(bounds[0]), "max": list(bounds[1])},
                        "sigma_s": sigma_s, "sigma_a": sigma_a, "phase_k": 0.3}]
    return fn


def chain(*fns):
    def fn(sc):
        for f in fns:
            f(sc)
    return fn


# Triangles of zero area among good ones (the loader drops them with a warning): a repeated
# corner, three corners on a line, all three at one point; and a quad of two good triangles.
DEGENERATE_OBJ = """v 0.2 0.3 0.2
v 0.4 0.3 0.2
v 0.4 0.3 0.4
v 0.2 0.3 0.4
v 0.3 0.3 0.3
v 0.6 0.6 0.6
f 1 3 2
f 1 4 3
f 1 1 2
f 1 5 3
f 6 6 6
f 2 2 3
"""

# A sheet folded onto itself: the same quad twice with opposite windings on shared corners, so
# every corner's face normals cancel (a zero-length sum wherever normals are averaged), and a
# crumpled fan whose eight faces alternate up and down around one vertex.
FOLDED_OBJ = """v 0.55 0.45 0.55
v 0.85 0.45 0.55
v 0.85 0.45 0.85
v 0.55 0.45 0.85
v 0.2 0.6 0.7
v 0.3 0.6 0.7
v 0.2 0.6 0.8
v 0.1 0.6 0.7
v 0.2 0.6 0.6
f 1 3 2
f 1 4 3
f 1 2 3
f 1 3 4
f 5 6 7
f 5 7 6
f 5 7 8
f 5 8 7
f 5 8 9
f 5 9 8
f 5 9 6
f 5 6 9
"""


# Slivers just above the loader's degeneracy bound (a triangle whose height is at most 1e-6 of
# its longest edge is dropped, shared/mesh.cpp): a needle, a cap and a fan, each 4e-6 thick.
SLIVER_OBJ = """v 0 0 0
v 1 0 0
v 0.5 4e-6 0
v 0 0 0.2
v 1 0 0.2
v 0.999999 4e-6 0.2
v 0 0.1 0.4
v 0.25 0.1 0.4
v 0.5 0.1 0.4
v 0.75 0.1 0.4
v 1 0.1 0.4
v 0.5 0.1 0.400004
f 1 2 3
f 4 5 6
f 7 8 12
f 8 9 12
f 9 10 12
f 10 11 12
"""

SCRIPT_FAR_AND_BACK = """-- the cube to the far corner of the world and back; the lamp moved
function on_frame(scene, frame, time)
    local cube = scene:object("cube")
    local lamp = scene:light("lamp")
    if frame == 1 then
        cube:set_position(9999999, 9999999, -9999999)
        lamp:set_position(0.5, 0.0, 0.5)
    elseif frame == 2 then
        cube:set_position(0.33, 0.15, 0.3)
        lamp:set_enabled(false)
    elseif frame == 3 then
        lamp:set_enabled(true)
        lamp:set_color(1e15, 1e15, 1e15)
        cube:set_position(0.5, 0.946, 0.5)
    end
end
"""

SCRIPT_CAMERA = """-- the camera into the cube, onto the wall and to the extreme fields of view
function on_frame(scene, frame, time)
    if frame == 1 then
        scene:set_camera({eye = {0.33, 0.15, 0.3}, fov_y = 179})
    elseif frame == 2 then
        scene:set_camera({eye = {0.5, 0.5, 1.0}, target = {0.5, 0.5, 0}, fov_y = 0.1})
    elseif frame == 3 then
        scene:set_camera({eye = {0.5, 0.5, -1.44}, target = {0.5, 0.5, 0}, fov_y = 39.3})
    end
end
"""


SCRIPT_OVERLAP = """-- the cube into the sphere, onto the lamp; the lid on ceiling and floor
function on_frame(scene, frame, time)
    local cube = scene:object("cube")
    local lid = scene:object("lid")
    if frame == 1 then
        cube:set_position(0.66, 0.16, 0.63)
        lid:set_position(0.5, 1.0, 0.5)
    elseif frame == 2 then
        cube:set_position(0.5, 0.946, 0.5)
        lid:set_position(0.5, 0.0, 0.5)
        scene:object("sphere"):set_albedo(0, 0, 0)
    elseif frame == 3 then
        cube:rotate(1, 1, 1, 1e-6)
        lid:set_position(0.5, 0.5, -1.44)
    end
end
"""


# Every edit in `bad` must be refused: an edit accepted raises an error, which the frame loop
# reports as "edit skipped" and the sweep counts as a failure. Then one valid edit, so the frames
# after the refusals still move the cube.
SCRIPT_REFUSED_EDITS = """-- positions, colours, albedos, cameras and rotations at 1e30, NaN and infinity
local nan, inf = 0 / 0, math.huge
local bad = {
    function(s) s:object("cube"):set_position(1e30, -1e30, 1e30) end,
    function(s) s:object("cube"):set_position(-1e30, 0.15, 0.3) end,
    function(s) s:object("cube"):set_position(nan, 0.15, 0.3) end,
    function(s) s:object("cube"):set_position(0.3, inf, 0.3) end,
    function(s) s:object("cube"):set_position(-1e7, 1e7, -1e7) end,
    function(s) s:object("cube"):rotate(0, 0, 0, 30) end,
    function(s) s:object("cube"):rotate(nan, 1, 0, 30) end,
    function(s) s:object("cube"):rotate(0, 1, 0, inf) end,
    function(s) s:light("lamp"):set_position(1e30, 0.5, 0.5) end,
    function(s) s:light("lamp"):set_position(0.5, nan, 0.5) end,
    function(s) s:light("lamp"):set_color(nan, 1, 1) end,
    function(s) s:light("lamp"):set_color(-1, 1, 1) end,
    function(s) s:light("lamp"):set_color(1e30, 1, 1) end,
    function(s) s:light("lamp"):set_color(inf, 1, 1) end,
    function(s) s:object("sphere"):set_albedo(nan, 0.5, 0.5) end,
    function(s) s:object("cube"):set_albedo(1.5, 0.5, 0.5) end,
    function(s) s:object("cube"):set_albedo(-0.5, 0.5, 0.5) end,
    function(s) s:set_camera({eye = {nan, 0.5, -1.44}}) end,
    function(s) s:set_camera({eye = {0.5, 0.5, -1e30}}) end,
    function(s) s:set_camera({fov_y = nan}) end,
    function(s) s:set_camera({fov_y = 1e30}) end,
    function(s) s:set_camera({eye = {0.5, 0.5, 0.5}, target = {0.5, 0.5, 0.5}}) end,
}
function on_frame(scene, frame, time)
    if frame == 1 then
        for i, f in ipairs(bad) do
            if pcall(f, scene) then error("edit " .. i .. " was accepted") end
        end
        scene:object("cube"):set_position(0.4, 0.15, 0.35)
    end
end
"""

# A unit cube for the mesh-scale cases (its `scale` flattens, mirrors or shrinks it).
CUBE_OBJ = """v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 3 4 8 7
f 2 3 7 6
f 1 5 8 4
"""


def box_mesh(scale):
    return edit(lambda sc: sc["objects"].append(
        {"name": "box2", "material": "white", "mesh": "cube.obj", "scale": scale,
         "transform": {"translate": [0.5, 0.4, 0.5]}}))


# One floor triangle 10^7 across (the world-size limit measures its reach from the origin: 5*10^6
# per corner) and one of side 10^-5 above the room's floor: every size relative to the scene's
# extent (texel size, radii, tolerances) meets a triangle 10^12 times smaller.
HUGE_AND_TINY_OBJ = """v -5e6 -0.001 -5e6
v -5e6 -0.001 5e6
v 5e6 -0.001 -5e6
v 0.5 0.3 0.5
v 0.50001 0.3 0.5
v 0.5 0.3 0.50001
f 1 2 3
f 4 6 5
"""


def gltf_shared_child(levels=40):
    """A glTF whose nodes each name the next as their child twice: 2^levels paths to one
    triangle (the reader recursed down every one of them; a node reached twice is refused)."""
    data = struct.pack("<9f", 0, 0, 0, 0, 0, 0.1, 0.1, 0, 0) + struct.pack("<3H", 0, 1, 2) + b"\0\0"
    nodes = [{"children": [i + 1, i + 1]} for i in range(levels)] + [{"mesh": 0}]
    return json.dumps({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(data).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [0.1, 0, 0.1]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "nodes": nodes, "scenes": [{"nodes": [0]}], "scene": 0})


def media_scene(sigma_s, sigma_a, light="point"):
    """Fog filling the room; the point light sits inside the medium."""
    return edit(chain(fog(sigma_s, sigma_a),
                      (lambda sc: sc["lights"].append(quad_light(0.4, 0.999, 2.0)))
                      if light == "both" else (lambda sc: None)))


class Case:
    def __init__(self, name, scene, why, files=None, script=None, runs=None, full_only=False,
                 refuse=None, ci=None, timeout=None, black=False, known=None, size=None):
        self.name, self.scene, self.why = name, scene, why
        self.files = files or {}          # extra files beside the scene: name -> text
        self.script = script              # Lua source, written as NAME.lua and named by the scene
        self.runs = runs                  # None: every run in RUNS, else names from it
        self.full_only = full_only        # only with --full
        self.refuse = refuse              # regex of the expected error (exit 1) instead of a render
        self.ci = ci                      # runs always in the CI selection (a regression's runs)
        self.timeout = timeout            # seconds per run instead of --timeout
        self.black = black                # every image must be 0 exactly: no light reaches them
        self.known = known or {}          # run -> a known failure, reported but not counted
        self.size = size                  # --size WxH instead of SIZE (not with black=True)


def cases():
    c = []
    add = lambda *a, **k: c.append(Case(*a, **k))  # noqa: E731
    add("baseline", cornell(), "the base scene every case changes")
    add("albedo_0", with_all_materials(cornell(), albedo=0.0), "every diffuse albedo exactly 0",
        black=True)
    add("albedo_1", with_all_materials(cornell(), albedo=1.0), "every diffuse albedo exactly 1")
    add("furnace_white", furnace(1.0), "closed box, albedo 1, point light inside, camera inside")
    add("furnace_white_quad", furnace(1.0, light="quad"),
        "closed box, albedo 1, quad light under the ceiling")
    add("furnace_black", furnace(0.0), "closed box, albedo 0", black=True)
    add("mirror_box", furnace(1.0, "mirror"), "closed box of perfect mirrors: specular loops",
        black=True)
    add("glass_box", furnace(1.0, "glass"), "closed box of glass walls, light and camera inside",
        black=True)
    add("light_zero", edit(lambda sc: sc["lights"][0].update(intensity=0)), "intensity 0",
        black=True)
    add("light_1e15", edit(lambda sc: sc["lights"][0].update(intensity=1e15)),
        "intensity 10^15 (the limit)")
    add("quad_1e15", edit(lambda sc: sc["lights"].__setitem__(0, quad_light(0.4, 0.999, 1e15))),
        "quad radiance 10^15")
    add("emission_1e15", edit(lambda sc: sc["materials"]["cube"].update(emission=1e15)),
        "a mesh light of emission 10^15 (the cube)")
    add("lights_disabled",
        edit(lambda sc: (sc["lights"].append(quad_light(0.4, 0.999, 2.0)),
                         [light.update(enabled=False) for light in sc["lights"]])),
        "every light disabled", black=True)
    add("no_lights", edit(lambda sc: sc.update(lights=[])), "no light at all", black=True)
    add("light_on_floor", edit(lambda sc: sc["lights"][0].update(position=[0.5, 0.0, 0.5])),
        "point light exactly on the floor")
    add("light_on_corner", edit(lambda sc: sc["lights"][0].update(position=[0.0, 1.0, 1.0])),
        "point light exactly in a corner of three walls")
    add("quad_on_ceiling",
        edit(lambda sc: sc["lights"].__setitem__(0, quad_light(0.4, 1.0, 2.0))),
        "quad light coplanar with the ceiling")
    add("light_in_cube", edit(lambda sc: sc["lights"][0].update(position=[0.33, 0.15, 0.3])),
        "point light inside the cube")
    add("light_in_glass", edit(lambda sc: sc["lights"][0].update(position=[0.66, 0.16, 0.63])),
        "point light inside the glass sphere")
    add("camera_in_cube", edit(lambda sc: sc["camera"].update(eye=[0.33, 0.15, 0.3])),
        "camera inside the cube")
    add("camera_on_wall", edit(lambda sc: sc["camera"].update(eye=[0.5, 0.5, 1.0])),
        "camera exactly on the back wall, looking out of the room")
    add("camera_on_floor", edit(lambda sc: sc["camera"].update(eye=[0.5, 0.0, -0.5])),
        "camera exactly in the floor's plane")
    add("fov_limits", edit(lambda sc: sc["camera"].update(fov_y=179)), "fov_y 179")
    add("far_1e7", moved(scaled(cornell(), 1000.0), (9998000.0, -9998000.0, 9998000.0)),
        "a 1000-unit box near (10^7, -10^7, 10^7): float resolves 1 unit there")
    add("world_1e6", scaled(cornell(), 1e6), "the box scaled to 10^6 units (walls 2*10^7 apart "
        "would pass the limit too; the camera sits at -1.44*10^6)")
    add("world_1e-4", scaled(cornell(), 1e-4), "the box scaled to 0.1 mm: absolute epsilons "
        "would swallow it")
    add("huge_texel", edit(settings(lightmap__texel_size=1e6)),
        "texel size 10^6: one texel per chart")
    add("tiny_texel", edit(settings(lightmap__texel_size=0.002)),
        "texel size 2 mm on a 1 m room: 1.4 M atlas texels (0.9 mm, 6.9 M, takes 30 s and 4 GB "
        "a run: docs/robustness.md)", full_only=True, runs=["render_iim", "render_gpu_pm",
                                                          "render_irradiance_cache"], timeout=120)
    add("slivers", edit(lambda sc: sc["objects"].append(
        {"name": "slivers", "material": "white", "mesh": "slivers.obj"})),
        "a mesh of sliver triangles", files={"slivers.obj": SLIVER_OBJ})
    add("degenerate_triangles", edit(lambda sc: sc["objects"].append(
        {"name": "degenerate", "material": "white", "mesh": "degenerate.obj"})),
        "zero-area triangles (a repeated corner, collinear corners, one point) among good ones",
        files={"degenerate.obj": DEGENERATE_OBJ})
    add("folded_sheet", edit(lambda sc: sc["objects"].append(
        {"name": "folded", "material": "cube", "mesh": "folded.obj"})),
        "a quad folded onto itself and a crumpled fan: each corner's face normals sum to zero",
        files={"folded.obj": FOLDED_OBJ})
    add("emissive_folded", edit(lambda sc: (
        sc["materials"].update(hot={"albedo": 0.5, "emission": 5.0}),
        sc["objects"].append({"name": "folded", "material": "hot", "mesh": "folded.obj"}))),
        "the folded sheet as a mesh light: two emitters on one plane facing apart",
        files={"folded.obj": FOLDED_OBJ})
    add("tiny_objects", edit(lambda sc: sc["objects"].extend([
        {"name": "speck", "material": "white", "shape": {"type": "box", "size": [1e-5] * 3},
         "transform": {"translate": [0.5, 0.5, 0.5]}},
        {"name": "dust", "material": "glass", "shape": {"type": "sphere", "radius": 1e-5},
         "transform": {"translate": [0.5, 0.4, 0.4]}}])),
        "a box of side 10^-5 and a glass sphere of radius 10^-5 in the 1-unit room")
    add("light_on_speck", edit(lambda sc: (
        sc["objects"].append({"name": "speck", "material": "white",
                              "shape": {"type": "box", "size": [1e-5] * 3},
                              "transform": {"translate": [0.5, 0.5, 0.5]}}),
        sc["lights"][0].update(position=[0.5, 0.5 + 5e-6, 0.5]))),
        "the point light on the top face of a box of side 10^-5")
    add("quad_into_floor", edit(lambda sc: sc["lights"].__setitem__(0, dict(
        quad_light(0.4, 0.0, 2.0), corners=[[0.4, 0.0, 0.4], [0.6, 0.0, 0.4], [0.6, 0.0, 0.6],
                                            [0.4, 0.0, 0.6]]))),
        "a quad light in the floor's plane facing down into the floor: nothing can be lit",
        black=True)
    add("quad_on_floor", edit(lambda sc: sc["lights"].__setitem__(0, dict(
        quad_light(0.4, 0.0, 2.0), corners=[[0.4, 0.0, 0.4], [0.4, 0.0, 0.6], [0.6, 0.0, 0.6],
                                            [0.6, 0.0, 0.4]]))),
        "a quad light lying in the floor's plane facing up (its corners on the floor)")
    add("emitter_on_wall", edit(lambda sc: (
        sc["materials"].update(hot={"albedo": 0.5, "emission": 3.0}),
        sc["objects"].append(quad("panel", "hot", (0.3, 0.3), (0.5, 0.5, 1.0), (1, 0, 0),
                                  -90.0)))),
        "an emissive quad exactly on the back wall (a mesh light coincident with a surface)")
    add("spot_in_wall", edit(lambda sc: sc["lights"].__setitem__(0, {
        "name": "lamp", "type": "spot", "position": [0.5, 0.5, 1.0], "direction": [0, 0, 1],
        "intensity": 5, "cone_outer": 30})),
        "a spot on the back wall pointing into it: nothing can be lit", black=True)
    add("albedo_over_1", edit(lambda sc: sc["materials"]["white"].update(albedo=1.0001)),
        "albedo above 1 (energy from nothing) is refused", refuse=r"albedo")
    add("coincident", edit(lambda sc: sc["objects"].extend([
        dict(copy.deepcopy(obj("cube")(sc)), name="cube2", material="red"),
        quad("floor2", "green", (1, 1), (0.5, 0, 0.5))])),
        "a second cube and a second floor exactly on the first (z-fighting)")
    add("glass_ior_1", edit(lambda sc: sc["materials"]["glass"].update(ior=1.0)), "glass ior 1")
    add("glass_ior_4", edit(lambda sc: sc["materials"]["glass"].update(ior=4.0)), "glass ior 4")
    add("mirror_cube", edit(lambda sc: sc["materials"]["cube"].update(type="mirror", albedo=1)),
        "a mirror cube beside the glass sphere")
    add("spot_narrow", edit(lambda sc: sc["lights"].__setitem__(0, {
        "name": "lamp", "type": "spot", "position": [0.5, 0.9, 0.5], "direction": [0, -1, 0],
        "intensity": 5, "cone_outer": 1e-4})), "a spot of 10^-4 degrees")
    add("sun_grazing", edit(lambda sc: sc["lights"].__setitem__(0, {
        "name": "lamp", "type": "sun", "direction": [1, -1e-6, 0], "irradiance": 1})),
        "a sun grazing the floor")
    add("media_sigma_0", edit(fog(0.0, 0.0)), "fog with sigma_s = sigma_a = 0")
    add("media_sigma_huge", edit(fog(1e6, 1e6)), "fog with sigma 10^6 (the limit)",
        ci=["reference_pt", "media"])
    add("media_scatter_only", edit(fog(1e3, 0.0)), "dense fog that only scatters")
    add("media_light_inside", media_scene(2.0, 0.5, light="both"),
        "point and quad light inside the fog")
    add("script_far_and_back", edit(lambda sc: sc.update(script="script_far_and_back.lua")),
        "a script moving the cube to (10^7, 10^7, -10^7) and back, the lamp onto the floor, "
        "off, on at 10^15", script=SCRIPT_FAR_AND_BACK)
    add("script_camera", edit(lambda sc: sc.update(script="script_camera.lua")),
        "a script putting the camera in the cube, on the wall, fov 179 and 0.1",
        script=SCRIPT_CAMERA)
    add("mixed_scale", edit(lambda sc: sc["objects"].append(
        quad("far_tile", "white", (1, 1), (9999000, 0, 9999000)))),
        "the 1-unit room plus a tile 10^7 away: every size relative to the scene's extent "
        "(default texel size, radii, tolerances) is 10^7 times the room")
    add("camera_tele", edit(lambda sc: sc["camera"].update(eye=[0.5, 0.5, -570], fov_y=0.1)),
        "fov 0.1 degrees from 570 units away")
    add("camera_far", edit(lambda sc: sc["camera"].update(eye=[0.5, 0.5, -9999999])),
        "the camera 10^7 away from a 1-unit room (depth range)")
    add("tiny_quad_light", edit(lambda sc: sc["lights"].__setitem__(
        0, quad_light(0.5, 0.99, 1e15, size=1e-5))), "a quad light of side 10^-5, radiance 10^15")
    add("emissive_slivers", edit(lambda sc: (
        sc["materials"].update(hot={"albedo": 0.5, "emission": 1e6}),
        sc["objects"].append({"name": "slivers", "material": "hot", "mesh": "slivers.obj"}))),
        "a mesh light made of sliver triangles", files={"slivers.obj": SLIVER_OBJ})
    add("spot_wide", edit(lambda sc: sc["lights"].__setitem__(0, {
        "name": "lamp", "type": "spot", "position": [0.5, 0.9, 0.5], "direction": [0, -1, 0],
        "intensity": 1e15, "cone_outer": 90, "cone_inner": 0})), "a spot of 90 degrees, 10^15")
    add("sun_1e15", edit(lambda sc: sc["lights"].__setitem__(0, {
        "name": "lamp", "type": "sun", "direction": [0.3, -1, 0.2], "irradiance": 1e15})),
        "a sun of irradiance 10^15 (on the open room)")
    add("lights_coincident", edit(lambda sc: sc.update(lights=[
        {"name": "l%d" % i, "type": "point", "position": [0.5, 0.5, 0.5], "intensity": 0.1}
        for i in range(64)])), "64 point lights at one point (kMaxLightSamples)")
    add("glass_noise_max", edit(lambda sc: sc["materials"]["glass"].update(
        ior=4.0, ior_noise={"amplitude": 3.0, "frequency": 1e6, "seed": 4294967295},
        interior={"sigma_s": 1e6, "sigma_a": 0, "phase_k": 0.999})),
        "glass of ior 4 with noise amplitude 3 at frequency 10^6, filled with a 10^6 medium")
    add("media_noise_max", edit(lambda sc: sc.update(media=[{
        "bounds": {"min": [0, 0, 0], "max": [1, 1, 1]}, "sigma_s": 10, "sigma_a": 1,
        "phase_k": -0.999, "noise": {"amplitude": 1, "frequency": 1e6, "seed": 0}}])),
        "fog whose density noise has amplitude 1 at frequency 10^6, phase k -0.999")
    add("media_face_on_eye", edit(lambda sc: sc.update(media=[{
        "bounds": {"min": [0.5, 0.5, -1.44], "max": [1, 1, 1]}, "sigma_s": 5, "sigma_a": 1,
        "phase_k": 0.999}])),
        "a medium whose min corner lies on the camera and the light on its face x = 0.5: view "
        "rays along its faces; the media method threw for a light on the grid's boundary",
        ci=["media", "render_iim"])
    add("media_thin", edit(lambda sc: sc.update(media=[{
        "bounds": {"min": [0, 0.5, 0], "max": [1, 0.500001, 1]}, "sigma_s": 1e6, "sigma_a": 0}])),
        "a medium slab 10^-6 thick of sigma 10^6")
    add("media_far", moved(scaled(edit(fog(0.5, 0.1)), 1000.0),
                            (9998000.0, -9998000.0, 9998000.0)),
        "fog in the 1000-unit box near (10^7, -10^7, 10^7)")
    huge_and_tiny = {"name": "huge_and_tiny", "material": "white", "mesh": "huge_and_tiny.obj"}
    add("huge_and_tiny_triangle", edit(lambda sc: (
        sc["objects"].append(huge_and_tiny), sc["settings"]["lightmap"].pop("texel_size"))),
        "one triangle 10^7 across under the floor and one of side 10^-5 in the room, the "
        "default texel size (from the scene's extent)",
        files={"huge_and_tiny.obj": HUGE_AND_TINY_OBJ})
    add("huge_and_tiny_fine_texels", edit(lambda sc: sc["objects"].append(huge_and_tiny)),
        "the same at the base's texel size 0.2 (a chart 5*10^7 texels across) is refused",
        files={"huge_and_tiny.obj": HUGE_AND_TINY_OBJ}, refuse=r"over 65536 texels wide",
        ci=["render_iim"])
    add("gltf_shared_child", edit(lambda sc: sc["objects"].append(
        {"name": "nodes", "mesh": "shared_child.gltf"})),
        "a glTF whose 40 nodes each name the next as a child twice (2^40 placements: a hang "
        "before) is refused naming the node", files={"shared_child.gltf": gltf_shared_child()},
        refuse=r"node 40: expected a node tree, got a node reached a second time",
        ci=["render_iim"])
    # Degenerate media (s13's NaN hunt): the phase function at both ends of its range and past
    # them, boxes of no volume, inside out or overlapping (refused by name), boxes sharing a face
    # or a corner, glass of ior 1 filled with a medium (refraction without bending, the medium
    # still there), its index noise at amplitude ior - 1 (n touches 1) at frequencies 10^-6 and
    # 10^6, a medium only in the glass around a light, and the light inside a dense fog box.
    for k in (0.999, -0.999):
        add("media_phase_%s" % ("forward" if k > 0 else "backward"),
            edit(lambda sc, k=k: sc.update(media=[{
                "bounds": {"min": [0, 0, 0], "max": [1, 1, 1]}, "sigma_s": 2, "sigma_a": 0,
                "phase_k": k}])),
            "fog of phase k %g (the limit), scattering only" % k)
    for k in (1.0, -1.0):
        add("media_phase_%s_refused" % ("plus" if k > 0 else "minus"),
            edit(lambda sc, k=k: sc.update(media=[{
                "bounds": {"min": [0, 0, 0], "max": [1, 1, 1]}, "sigma_s": 2, "sigma_a": 0,
                "phase_k": k}])),
            "phase k %g (Schlick's phase is a delta there) is refused" % k, refuse=r"phase_k",
            ci=["render_iim"])
    add("media_flat_refused", edit(fog(1.0, 0.1, bounds=((0, 0.5, 0), (1, 0.5, 1)))),
        "a medium box of zero height is refused", refuse=r"bounds", ci=["render_iim"])
    add("media_inverted_refused", edit(fog(1.0, 0.1, bounds=((1, 1, 1), (0, 0, 0)))),
        "a medium box with min above max is refused", refuse=r"bounds", ci=["render_iim"])
    add("media_overlap_refused", edit(lambda sc: sc.update(media=[
        {"bounds": {"min": [0, 0, 0], "max": [0.6, 1, 1]}, "sigma_s": 1, "sigma_a": 0.1},
        {"bounds": {"min": [0.4, 0, 0], "max": [1, 1, 1]}, "sigma_s": 3, "sigma_a": 0.1}])),
        "two overlapping medium boxes are refused", refuse=r"overlap", ci=["render_iim"])
    add("media_touching", edit(lambda sc: sc.update(media=[
        {"bounds": {"min": [0, 0, 0], "max": [0.5, 1, 1]}, "sigma_s": 1, "sigma_a": 0.1,
         "phase_k": 0.5},
        {"bounds": {"min": [0.5, 0, 0], "max": [1, 1, 1]}, "sigma_s": 8, "sigma_a": 0,
         "phase_k": -0.5}])),
        "two medium boxes sharing the face x = 0.5, the light on it (x = 0.5)")
    add("media_corner_boxes", edit(lambda sc: sc.update(media=[
        {"bounds": {"min": [0, 0, 0], "max": [0.5, 0.5, 0.5]}, "sigma_s": 4, "sigma_a": 0},
        {"bounds": {"min": [0.5, 0.5, 0.5], "max": [1, 1, 1]}, "sigma_s": 4, "sigma_a": 0}])),
        "two medium boxes meeting at one corner, the light near it")
    add("media_glass_ior_1", edit(lambda sc: sc["materials"]["glass"].update(
        ior=1.0, interior={"sigma_s": 20, "sigma_a": 1, "phase_k": 0.3})),
        "glass of ior 1 (no bending, no reflection) filled with a medium")
    for f in (1e-6, 1e6):
        add("media_glass_noise_%s" % ("low" if f < 1 else "high"),
            edit(lambda sc, f=f: sc["materials"]["glass"].update(
                ior=1.5, ior_noise={"amplitude": 0.5, "frequency": f, "seed": 7},
                interior={"sigma_s": 5, "sigma_a": 0.5, "phase_k": -0.999,
                          "noise": {"amplitude": 1, "frequency": f, "seed": 2}})),
            "glass of ior 1.5 with index noise of amplitude 0.5 (n down to 1) at frequency %g, "
            "filled with noisy fog" % f)
    add("media_light_in_filled_glass", edit(lambda sc: (
        sc["materials"]["glass"].update(interior={"sigma_s": 50, "sigma_a": 5}),
        sc["lights"][0].update(position=[0.66, 0.16, 0.63]))),
        "a point light inside the glass sphere, which is filled with a dense medium")
    # Not `black`: e^-55 of the light leaves, and the images hold values of 1e-24 (pt 1e-33).
    # gpu_pm ignored media and lit the room (indirect mean 0.21 at 16^2, now < 1e-26;
    # GpuPmTest.PhotonsThroughFogLoseBeerLambertAlongTheirPaths holds it). The media method at
    # the sweep's 8-voxel grid shows the box glowing (up to 0.57; 0 at 32 and 64 voxels): the
    # grid's resolution, not a robustness failure.
    add("media_dense_around_light",
        edit(fog(1e3, 1e2, bounds=((0.4, 0.8, 0.4), (0.6, 0.99, 0.6)))),
        "the point light inside a small box of dense fog (sigma_t 1100 over at least 5 cm: "
        "e^-55 of the light leaves it)", ci=["render_gpu_pm"])
    # Every tracer over the shared ray interface once stored photons on the ceiling's front face
    # inside the cube (Embree's order among coincident faces); the cube's back face now wins
    # (shared/coincident_hits.h). gpu_pm stored photons on the cube's inside (back faces) and its
    # kernel reached them through the walls, coplanar or not; back faces now absorb in its trace
    # too. VPL shadow maps 8 texels across (direct.map_size, the base's) offset the ceiling
    # below the maps' horizon, out of the map, and lit it; the offset now stays above it. Pinned
    # in CI through every method that leaked.
    add("light_in_box_coplanar", edit(lambda sc: obj("cube")(sc)["transform"].update(
        translate=[0.5, 0.85, 0.5])),
        "the lamp inside the cube whose top face lies in the ceiling's plane: nothing can "
        "light the room", black=True,
        ci=["reference_pt", "reference_pm", "render_vpl", "render_iim", "render_gpu_pm",
            "render_irradiance_cache", "render_cpu_gather", "render_frame_ms",
            "render_vpl_direct"])
    add("light_in_box_below_ceiling", edit(chain(
        lambda sc: obj("cube")(sc)["transform"].update(translate=[0.5, 0.8, 0.5]),
        lambda sc: sc["lights"][0].update(position=[0.5, 0.896, 0.5]))),
        "the same lamp and cube 5 cm lower, nothing coplanar: nothing can light the room",
        black=True, ci=["render_gpu_pm", "render_vpl_direct"])
    # Charts cut into tiles near the contacts (lightmap.refine_tile) put corners on the walls'
    # outlines where the wall beside has its edge whole; the shadow volumes' seam sides no longer
    # met there and a line of light ran along the seam (gpu/shadow_volumes.cpp splits the edge;
    # the line was 5 pixels at 128x128 and falls between the pixels at 16x16, so the seams are
    # held by ShadowVolumes.TJunctionsBetweenTiledWallsStillCancelAlongTheSeams; this case runs
    # the tiled layout through the renderers).
    add("light_in_box_below_ceiling_tiled", edit(chain(
        lambda sc: obj("cube")(sc)["transform"].update(translate=[0.5, 0.8, 0.5]),
        lambda sc: sc["lights"][0].update(position=[0.5, 0.896, 0.5]),
        settings(lightmap__refine_factor=4, lightmap__refine_budget=10, lightmap__refine_tile=1,
                 lightmap__refine_reach=1))),
        "light_in_box_below_ceiling with the charts cut into tiles near the contacts",
        black=True, ci=["render_gpu_pm", "render_iim"])
    add("photons_escape", edit(lambda sc: (
        sc.update(objects=[o for o in sc["objects"] if o["name"] == "floor"]),
        sc["lights"].__setitem__(0, dict(quad_light(0.4, 0.5, 2.0), corners=[
            [0.4, 0.5, 0.4], [0.4, 0.5, 0.6], [0.6, 0.5, 0.6], [0.6, 0.5, 0.4]])))),
        "a floor under a quad light facing up: every photon escapes (empty photon maps, no "
        "VPLs, no records)")
    add("lone_floor", edit(lambda sc: sc.update(
        objects=[o for o in sc["objects"] if o["name"] == "floor"])),
        "one quad and a point light: photons leave after one bounce")
    add("quad_sliver_light", edit(lambda sc: sc["lights"].__setitem__(0, {
        "name": "lamp", "type": "quad", "radiance": 1e6,
        "corners": [[0.4, 0.9, 0.4], [0.6, 0.9, 0.4], [0.6, 0.9, 0.400001],
                    [0.4, 0.9, 0.400001]]})), "a quad light 0.2 by 10^-6")
    add("camera_up_near_view", edit(lambda sc: sc["camera"].update(
        eye=[0.5, 0.9, 0.5], target=[0.5, 0.0, 0.5], up=[1.2e-4, 1, 0])),
        "looking straight down with up 1.2*10^-4 from the view axis (the limit is 10^-4)")
    add("light_at_eye", edit(lambda sc: sc["lights"][0].update(position=[0.5, 0.5, -1.44])),
        "the point light exactly at the camera, outside the open room")
    add("script_overlap", edit(lambda sc: (
        sc.update(script="script_overlap.lua"),
        sc["objects"].append({"name": "lid", "material": "white", "dynamic": True,
                              "shape": {"type": "quad", "size": [0.3, 0.3]},
                              "transform": {"translate": [0.5, 0.6, 0.5]}}))),
        "a script moving the cube into the glass sphere, onto the lamp and the lid onto the "
        "ceiling and the floor (coplanar)", script=SCRIPT_OVERLAP)
    # Settings at the ends of their ranges (shared/settings.h), each through the runs that read
    # it; counts only where the end is cheap at 16x16.
    iim = ["render_iim", "render_cpu_gather"]
    for name, runs_, kv in [
        ("rc_radius_0", ["render_irradiance_cache"], {"rc.min_radius": 0, "rc.max_radius": 0}),
        ("rc_min_above_max", ["render_irradiance_cache"],
         {"rc.min_radius": 10, "rc.max_radius": 0}),
        ("rc_extremes", ["render_irradiance_cache"],
         {"rc.accuracy": 0.01, "rc.theta_strata": 1, "rc.phi_strata": 3,
          "rc.temporal_accuracy": 1e-6, "rc.max_lifespan": 1}),
        ("rc_loose", ["render_irradiance_cache"],
         {"rc.accuracy": 1, "rc.temporal_accuracy": 1e6, "rc.max_lifespan": 1000000,
          "rc.source": "direct", "rc.shadow_samples": 1}),
        ("gpu_pm_radius_min", ["render_gpu_pm"],
         {"gpu_pm.radius": 1e-5, "gpu_pm.low_res": 8, "gpu_pm.edge_normal": -1,
          "gpu_pm.edge_distance": 0}),
        ("gpu_pm_radius_max", ["render_gpu_pm"],
         {"gpu_pm.radius": 10, "gpu_pm.low_res": 1, "gpu_pm.edge_normal": 1,
          "gpu_pm.edge_distance": 100, "gpu_pm.bounces": 16, "gpu_pm.binning": "brute"}),
        ("vpl_clamp_max", ["render_vpl"], {"vpl.clamp": 1e30}),
        ("vpl_random_walk", ["render_vpl"],
         {"vpl.source": "random_walk", "vpl.walk_bounces": 1000, "vpl.walk_paths": 4,
          "vpl.interleave": 4, "vpl.labels": True, "vpl.resolution_divisor": 64}),
        ("vpl_cpu", ["render_vpl"], {"vpl.backend": "cpu", "vpl.tiles": False}),
        ("aim_extremes", iim,
         {"aim.knn": 10000, "aim.delta_threshold": 1e30, "aim.surfaces_per_frame": 1}),
        ("gather_extremes", iim,
         {"gather.plane_half_width": 0.1, "gather.plane_resolution": 2,
          "gather.border_correction": "renormalize", "gather.blend_frames": 1000,
          "gather.cpu_rays": 1, "gather.specular_bounces": 64, "gather.refine_footprint": 1,
          "gather.hemisphere": "plane"}),
        ("gather_wide", iim,
         {"gather.plane_half_width": 100, "gather.border_correction": "stretch_radial",
          "gather.specular_bounces": 0}),
        ("photon_extremes", QUICK_RUNS,
         {"photons.max_bounces": 1000, "photons.path_tolerance": 0, "photons.groups": 1,
          "photons.photons_per_group": 1, "caustics.kernel_k": 32,
          "caustics.kernel_photons": 1000000, "caustics.tile_size": 4}),
        ("photon_tolerance_1", QUICK_RUNS,
         {"photons.path_tolerance": 1, "caustics.kernel_k": 0, "caustics.tile_size": 512,
          "caustics.photons": 0}),
        ("lightmap_extremes", QUICK_RUNS,
         {"lightmap.crease_angle": 180, "lightmap.chart_cone": 60, "lightmap.gutter": 16,
          "lightmap.refine_factor": 16, "lightmap.refine_distance": 1e6,
          "lightmap.refine_budget": 1}),
        ("lightmap_crease_0", QUICK_RUNS,
         {"lightmap.crease_angle": 0, "lightmap.chart_cone": 1}),
    ]:
        add(name, edit(settings(**{k.replace(".", "__"): v for k, v in kv.items()})),
            "settings at the ends of their ranges: " + ", ".join(
                "%s=%s" % (k, json.dumps(v)) for k, v in kv.items()), runs=runs_)
    # Session 15: the input classes the sweep missed.
    add("size_1x1", cornell(), "--size 1x1: one pixel through every renderer", size="1x1")
    add("size_16384x1", cornell(), "--size 16384x1: the widest image, one row",
        size="16384x1")
    add("albedo_denormal", edit(lambda sc: (
        sc["materials"]["white"].update(albedo=1e-320),
        sc["materials"]["cube"].update(albedo=-0.0))),
        "albedo 1e-320 (a double denormal, 0 as a float) and -0.0")
    add("mesh_flattened", box_mesh([0.2, 1e-30, 0.2]),
        "a cube mesh scaled flat: its sides dropped (warned), top and bottom coincident and "
        "facing apart", files={"cube.obj": CUBE_OBJ})
    add("mesh_mirrored", box_mesh(-0.2), "a cube mesh scaled by -0.2 (mirrored, winding fixed)",
        files={"cube.obj": CUBE_OBJ})
    add("only_cube", edit(lambda sc: sc.update(
        objects=[o for o in sc["objects"] if o["name"] == "cube"])),
        "one cube and the lamp in the void: most rays and photons escape")
    add("script_refused_edits", edit(lambda sc: sc.update(script="script_refused_edits.lua")),
        "a script's edits at 1e30, NaN and infinity, a zero axis, a camera with eye = target: "
        "each refused (pcall), then one valid move", script=SCRIPT_REFUSED_EDITS,
        ci=["render_iim"])
    for name, fn, why, pattern in [
        ("albedo_nan_refused",
         lambda sc: sc["materials"]["white"].update(albedo=float("nan")),
         "albedo NaN (written as the bare NaN JSON does not have)", r"line \d+, column \d+"),
        ("intensity_inf_refused", lambda sc: sc["lights"][0].update(intensity=float("inf")),
         "intensity Infinity", r"line \d+, column \d+"),
        ("intensity_negative_refused", lambda sc: sc["lights"][0].update(intensity=-1),
         "a negative intensity", r"/lights/0/intensity: expected a number in \[0, 1e\+15\]"),
        ("quad_zero_area_refused",
         lambda sc: sc["lights"].__setitem__(0, quad_light(0.4, 0.999, 2.0, size=0.0)),
         "a quad light of zero area", r"/lights/0/corners: expected a parallelogram of non-zero"),
        ("no_objects_refused", lambda sc: sc.update(objects=[]), "a scene without objects",
         r"/objects: expected at least one object"),
    ]:
        add(name, edit(fn), why + " is refused", refuse=pattern)
    for name, scale, pattern in [("mesh_scale_0_refused", 0, r"expected non-zero scale"),
                                 ("mesh_scale_1e-30_refused", 1e-30,
                                  r"makes all 12 triangles degenerate")]:
        add(name, box_mesh(scale), "a mesh scaled by %g is refused" % scale, refuse=pattern,
            files={"cube.obj": CUBE_OBJ})
    # The same extremes in the white furnace: nothing absorbed, so every cap is reached.
    add("furnace_caps", chain_scene(furnace(1.0), settings(
        photons__max_bounces=1000, gpu_pm__bounces=16, vpl__source="random_walk",
        vpl__walk_bounces=1000, vpl__walk_paths=4, gather__specular_bounces=64)),
        "the white furnace with photons.max_bounces 1000, gpu_pm.bounces 16, random-walk VPLs "
        "of 1000 bounces")
    return c


def chain_scene(scene, fn):
    fn(scene)
    return scene


# --- runs -------------------------------------------------------------------------------------

# name -> (arguments after SCENE, images written beside OUT, which cases it applies to)
IMAGES_AOV = ["", ".direct", ".indirect", ".caustics", ".specular", ".volume"]


def runs():
    r = {}
    for method in ("iim", "gpu_pm", "vpl", "irradiance_cache"):
        r["render_" + method] = (["render", "-n", FRAMES, "--size", SIZE, "--aov", "-q",
                                  "--indirect", method], IMAGES_AOV)
    r["render_cpu_gather"] = (["render", "-n", FRAMES, "--size", SIZE, "--aov", "-q",
                               "--gather", "cpu"], IMAGES_AOV)
    r["render_vpl_direct"] = (["render", "-n", FRAMES, "--size", SIZE, "-q",
                               "--set", "direct.method=vpl"], [""])
    r["reference_pt"] = (["reference", "-m", "pt", "--spp", "2", "--size", SIZE, "-q"],
                         IMAGES_AOV)
    r["reference_pm"] = (["reference", "-m", "pm", "--spp", "1", "--size", SIZE, "-q",
                          "--photons", "2000", "--caustic-photons", "2000", "--gather-rays", "4",
                          "--knn", "8", "--caustic-knn", "8"], IMAGES_AOV)
    r["converge"] = (["converge", "-n", FRAMES, "--size", SIZE, "-q", "--component", "full",
                      "--ref-spp", "1", "--ref-photons", "2000"], [])
    r["render_frame_ms"] = (["render", "-n", FRAMES, "--size", SIZE, "-q", "--frame-ms", "0.01"],
                            [""])
    r["media"] = (["media", "--size", SIZE, "--grid", "8", "--photons", "2000"], [""])
    return r


QUICK_RUNS = ["render_iim", "render_gpu_pm", "render_vpl", "render_irradiance_cache",
              "reference_pt", "reference_pm"]


def selected(case, index, run_name, mode):
    """Whether the mode runs this case's run. ci: each case once, through the runs in turn
    (RUN_CYCLE; a case with its own list: the first that applies), or its pinned `ci` runs, so
    every method meets a share of the cases within the CI budget; cases with media only where
    pinned (the media method takes seconds a run at any size); methods: QUICK_RUNS; full: every
    run."""
    if not applies(case, run_name):
        return False
    if mode == "full":
        return True
    if mode == "methods":
        return run_name in QUICK_RUNS
    if case.ci:
        return run_name in case.ci
    if has_media(case):
        return False  # the media method takes seconds a run at any size: methods and full only
    candidates = [r for r in RUN_CYCLE if applies(case, r)]
    if not candidates:
        return False
    return run_name == candidates[index % len(candidates)]


RUN_CYCLE = QUICK_RUNS + ["converge"]


def has_media(case):
    return bool(case.scene.get("media")) or any(
        "interior" in m for m in case.scene["materials"].values())


def applies(case, run_name):
    if case.runs is not None:
        return run_name in case.runs
    if run_name == "media":
        return bool(case.scene.get("media"))
    if run_name == "reference_pm" and has_media(case):
        return False  # pm refuses media by design (docs/scene-format.md, "Media")
    return True


def check_images(afterglow, out, suffixes):
    """Problems with the images a run wrote: missing, unreadable or not finite. `compare` reads
    two images at once and refuses either if it holds a NaN or an infinity."""
    problems, paths = [], []
    stem = out[:-len(".exr")]
    for s in suffixes:
        path = stem + s + ".exr"
        if os.path.exists(path):
            paths.append(path)
        else:
            problems.append("missing " + os.path.basename(path))
    for i in range(0, len(paths), 2):
        pair = paths[i:i + 2] if i + 1 < len(paths) else [paths[i], paths[i]]
        p = run_compare(afterglow, pair)
        if p is None:
            problems.append("compare %s: over %g s" % (os.path.basename(pair[0]),
                                                        COMPARE_TIMEOUT))
        elif p.returncode != 0:
            problems.append(p.stderr.strip().splitlines()[-1] if p.stderr.strip()
                            else "compare exit %d" % p.returncode)
    return problems


def write_black_exr(path, width, height):
    """An uncompressed RGB 32-bit float OpenEXR image of zeros (the file layout of the OpenEXR
    specification: magic, version 2, header attributes, a line offset table, one scan line per
    chunk), to compare images against: `afterglow compare IMAGE BLACK` has RMSE 0 exactly when
    every value of IMAGE is 0."""
    def attr(name, kind, data):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data
    channels = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR")
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    header = (b"\x76\x2f\x31\x01" + struct.pack("<i", 2) +
              attr("channels", "chlist", channels + b"\0") +
              attr("compression", "compression", b"\0") +
              attr("dataWindow", "box2i", box) + attr("displayWindow", "box2i", box) +
              attr("lineOrder", "lineOrder", b"\0") +
              attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
              attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)) +
              attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    line = 3 * 4 * width
    first = len(header) + 8 * height
    offsets = b"".join(struct.pack("<Q", first + y * (8 + line)) for y in range(height))
    lines = b"".join(struct.pack("<ii", y, line) + bytes(line) for y in range(height))
    with open(path, "wb") as f:
        f.write(header + offsets + lines)


def check_black(afterglow, out, suffixes, black):
    """Problems where an image that must be black exactly (no light reaches it) is not."""
    problems = []
    stem = out[:-len(".exr")]
    for s in suffixes:
        path = stem + s + ".exr"
        if not os.path.exists(path):
            continue
        p = run_compare(afterglow, ["--json", path, black])
        if p is None:
            problems.append("compare %s with black: over %g s" % (os.path.basename(path),
                                                                  COMPARE_TIMEOUT))
            continue
        try:
            rmse = json.loads(p.stdout)["rmse"]
        except (ValueError, KeyError):
            problems.append("compare with black: " + (p.stderr.strip() or p.stdout.strip()))
            continue
        if rmse != 0.0:
            problems.append("%s: RMSE %g against black; expected 0 (no light reaches it)" % (
                os.path.basename(path), rmse))
    return problems


def check_csv(path):
    """Problems with converge's CSV: missing, or a NaN or infinite number in it."""
    if not os.path.exists(path):
        return ["missing " + os.path.basename(path)]
    with open(path) as f:
        rows = f.read().splitlines()
    for row in rows[1:]:
        for cell in row.split(","):
            try:
                if not math.isfinite(float(cell)):
                    return ["%s: %s" % (os.path.basename(path), row[:200])]
            except ValueError:
                pass
    return [] if len(rows) > 1 else [os.path.basename(path) + ": no rows"]


def process_stopped(pid):
    """Whether the process is stopped (SIGSTOP, a debugger): state T or t in /proc/PID/stat."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] in ("T", "t")
    except (OSError, IndexError):
        return False


def run_limited(argv, folder, timeout):
    """Runs argv; returns (CompletedProcess, seconds), or (None, seconds) when it ran past
    timeout. The limit counts only time the process could run: on a shared machine another
    user's tools may stop it (SIGSTOP) for a while, which is not a hang. Polls every 50 ms and
    counts at most 0.2 s a poll, so a pause of this script is not counted either."""
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(argv, stdout=out, stderr=err, text=True, cwd=folder)
        counted, last = 0.0, time.monotonic()
        while proc.poll() is None:
            time.sleep(0.05)
            now = time.monotonic()
            if not process_stopped(proc.pid):
                counted += min(now - last, 0.2)
            last = now
            if counted > timeout:
                proc.kill()
                proc.wait()
                return None, counted
        out.seek(0)
        err.seek(0)
        return subprocess.CompletedProcess(argv, proc.returncode, out.read(), err.read()), counted


COMPARE_TIMEOUT = 60.0  # seconds `afterglow compare` may take on two small images


def run_compare(afterglow, args):
    """`afterglow compare ARGS`: the CompletedProcess, or None past COMPARE_TIMEOUT, counted as
    the runs are (time stopped by other sessions' tools is not counted; a plain subprocess
    timeout once ended the whole sweep with an exception on the shared machine)."""
    p, _ = run_limited([afterglow, "compare"] + args, None, COMPARE_TIMEOUT)
    return p


def run_one(afterglow, folder, case, run_name, args, suffixes, timeout):
    scene_path = os.path.join(folder, case.name + ".json")
    if case.size:
        args = [case.size if i > 0 and args[i - 1] == "--size" else a
                for i, a in enumerate(args)]
    out = os.path.join(folder, "%s.%s.exr" % (case.name, run_name))
    if args[0] == "converge":  # a CSV of per-frame errors instead of images
        out = out[:-len(".exr")] + ".csv"
        argv = [afterglow, "converge", scene_path, "--csv", out, "--plot", "", "--cache",
                os.path.join(folder, "reference-cache")] + args[1:]
    else:
        argv = [afterglow, args[0], scene_path, "-o", out] + args[1:]
    p, seconds = run_limited(argv, folder, timeout)
    if p is None:
        return "FAIL", "over the %g s limit (hang?)" % timeout, seconds, argv
    err = p.stderr.strip()
    last = err.splitlines()[-1] if err else ""
    if p.returncode < 0 or p.returncode not in (0, 1):
        return "FAIL", "exit %d (crash?): %s" % (p.returncode, last[-300:]), seconds, argv
    if case.refuse is not None:
        if p.returncode == 1 and re.search(case.refuse, err):
            return "ok", "refused: " + last[-200:], seconds, argv
        return "FAIL", "expected an error matching %r, got exit %d: %s" % (
            case.refuse, p.returncode, last[-200:]), seconds, argv
    if p.returncode == 1:
        return "FAIL", "refused a valid scene: " + last[-300:], seconds, argv
    problems = check_images(afterglow, out, suffixes) if suffixes else check_csv(out)
    if not problems and case.black and suffixes:
        problems = check_black(afterglow, out, suffixes, os.path.join(folder, "black.exr"))
    if problems:
        return "FAIL", "; ".join(problems)[:400], seconds, argv
    # A NaN warning from an image writer, or a scripted edit refused (the case would not test
    # what it says).
    warnings = [line for line in err.splitlines()
                if "NaN" in line or "infinite" in line or "edit skipped" in line]
    if warnings:
        return "FAIL", warnings[0][-300:], seconds, argv
    return "ok", "", seconds, argv


def write_case(folder, case):
    with open(os.path.join(folder, case.name + ".json"), "w") as f:
        json.dump(case.scene, f, indent=1)
    for name, text in case.files.items():
        with open(os.path.join(folder, name), "w") as f:
            f.write(text)
    if case.script is not None:
        with open(os.path.join(folder, case.scene["script"]), "w") as f:
            f.write(case.script)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--afterglow", default=os.path.join(ROOT, "build", "afterglow"))
    ap.add_argument("--mode", choices=["ci", "methods", "full"], default="ci",
                    help="ci (default): each case through one run in turn, 117 runs; "
                    "methods: every case through every indirect method and both references; "
                    "full: every run (CPU gather, VPL shadows, frame-time target, converge, "
                    "media) and the slow cases")
    ap.add_argument("-j", "--jobs", type=int, default=2)
    ap.add_argument("--only", default="", help="regex on CASE/RUN")
    ap.add_argument("--every", type=int, default=1,
                    help="of each run (method) in the selection, only every Nth case, from the "
                    "first: every run keeps at least one case (the sanitized suite runs --mode ci "
                    "--every 2; the Release suite all of it)")
    ap.add_argument("--keep", default="", help="write scenes and images here and keep them")
    ap.add_argument("--timeout", type=float, default=120.0,
                    help="seconds a run may take (time it spent stopped not counted)")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    a = ap.parse_args(argv)

    all_cases = cases()
    if a.list:
        for case in all_cases:
            print("%-22s %s%s" % (case.name, case.why, " (full)" if case.full_only else ""))
        return 0
    afterglow = os.path.abspath(a.afterglow)
    if subprocess.run([afterglow, "glinfo"], capture_output=True).returncode != 0:
        print("no GL context: skipped")
        return 77
    folder = os.path.abspath(a.keep) if a.keep else tempfile.mkdtemp(prefix="ag-robust-")
    os.makedirs(folder, exist_ok=True)
    w, h = (int(v) for v in SIZE.split("x"))
    write_black_exr(os.path.join(folder, "black.exr"), w, h)
    run_table = runs()
    jobs = []
    for index, case in enumerate(all_cases):
        if case.full_only and a.mode != "full":
            continue
        write_case(folder, case)
        for run_name, (args, suffixes) in run_table.items():
            if not selected(case, index, run_name, a.mode):
                continue
            if a.only and not re.search(a.only, case.name + "/" + run_name):
                continue
            jobs.append((case, run_name, args, suffixes))
    seen = {}
    kept = []
    for job in jobs:
        nth = seen.get(job[1], 0)
        seen[job[1]] = nth + 1
        if nth % max(1, a.every) == 0:
            kept.append(job)
    jobs = kept
    start = time.monotonic()
    failures = 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        futures = {pool.submit(run_one, afterglow, folder, case, run_name, args, suffixes,
                               case.timeout or a.timeout): (case, run_name)
                   for case, run_name, args, suffixes in jobs}
        for fut in concurrent.futures.as_completed(futures):
            case, run_name = futures[fut]
            status, why, seconds, cmd = fut.result()
            if run_name in case.known:
                status, why = ("xfail", case.known[run_name]) if status == "FAIL" else (
                    "xpass", "known to fail, passed: " + case.known[run_name])
            failures += status == "FAIL"
            print("%-4s %-22s %-24s %6.2f s %s" % (status, case.name, run_name, seconds, why),
                  flush=True)
            if status == "FAIL":
                print("     " + " ".join(cmd), flush=True)
    print("%d runs, %d failed, %.1f s (scenes in %s)" % (
        len(jobs), failures, time.monotonic() - start, folder))
    if not a.keep:
        shutil.rmtree(folder, ignore_errors=True)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
