"""Afterglow: progressive global illumination in dynamic scenes (Larsen 2004), from Python.

    import afterglow
    scene = afterglow.Scene.load("scenes/cornell.json")
    pipeline = afterglow.Pipeline(scene, size=(64, 64))
    pipeline.run(10)                       # frames; the GIL is released meanwhile
    frame = pipeline.image()               # float32 (H, W, 3), linear radiance
    scene.object("cube").translate((0.1, 0, 0))
    pipeline.run(10)                       # the pipeline sees the edit

Scenes, their edits (the API Lua scripts use), the pipeline, reference renders, metrics and the
convergence study of `afterglow converge` come from the C++ library (afterglow._afterglow);
tiles of reference renders and the Dask sweep (afterglow.sweep, `tools/sweep`) are Python.
See docs/python.md.
"""
import numpy as _np

from ._afterglow import (  # noqa: F401
    InputError,
    Light,
    Object,
    Pipeline,
    Scene,
    __version__,
    compare,
    converge,
    error_heatmap,
    frame_terms,
    read_image,
    render_reference,
    write_image,
)

#: The images a reference render returns: the full image and its four terms.
components = ["full"] + list(frame_terms)


def tiles(width, height, tile):
    """Regions (x, y, w, h) covering a width x height image in tile x tile pieces, row by row."""
    if tile < 1:
        raise ValueError(f"tile: expected a size >= 1, got {tile}")
    return [(x, y, min(tile, width - x), min(tile, height - y))
            for y in range(0, height, tile) for x in range(0, width, tile)]


def merge_tiles(parts, width, height):
    """Puts reference renders of regions together: `parts` is a list of (region, result) with
    result a render_reference() dict; returns a dict component -> float32 (H, W, 3). Every pixel
    must be covered exactly once (ValueError otherwise); the pixels are copied, not recomputed, so
    the merge equals the whole-image render bit for bit."""
    merged = {c: _np.zeros((height, width, 3), _np.float32) for c in components}
    covered = _np.zeros((height, width), _np.int32)
    for (x, y, w, h), result in parts:
        if x < 0 or y < 0 or x + w > width or y + h > height:
            raise ValueError(f"tile {(x, y, w, h)} is not inside the {width}x{height} image")
        for c in components:
            if result[c].shape != (h, w, 3):
                raise ValueError(f"tile {(x, y, w, h)}: {c} image has shape {result[c].shape}")
            merged[c][y:y + h, x:x + w] = result[c]
        covered[y:y + h, x:x + w] += 1
    if (covered != 1).any():
        bad = int((covered != 1).sum())
        raise ValueError(f"{bad} pixels are covered by no tile or by several")
    return merged
