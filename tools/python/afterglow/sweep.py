"""Sweeps on Dask (`tools/sweep SPEC.json`, docs/python.md): a grid of convergence runs (scenes x
indirect methods x named settings x seeds x baselines) and the reference renders they are
measured against, as tasks of a Dask graph on a LocalCluster or on an existing scheduler.

A reference (the scene's state at the end of its edit script) is split into image tiles, one task
each; every pixel's samples depend on its place in the whole image only, so the merged tiles equal
the single-process render bit for bit. Each convergence run depends on its scene's merged
reference. Results: one table (sweep.csv; sweep.parquet too where pyarrow is installed) with a row
per frame of every run, summary.csv with a row per task (status, attempts, error, settle
analysis), the references (.npy exact, .exr, .png), one CSV per run and the plots
tools/plot_convergence.py draws for `afterglow converge`. Failed tasks are retried (`retries`) and
then reported in summary.csv and on stderr; the sweep then exits non-zero.

The spec (paths relative to the spec file; every key but "scenes" optional):

    {
      "scenes": [{"path": "scenes/cornell.json", "script": "scenes/cornell_cube_jump.lua",
                  "name": "cornell"}, "scenes/two_rooms.json"],
      "methods": ["iim"],                       # settings.indirect.method values
      "settings": {"default": {}, "fewer_groups": {"photons": {"groups": 32}}},
      "seeds": [1],                             # settings.seed of the pipeline
      "baselines": ["selective"],               # selective, full, full-budget
      "frames": 60, "size": [48, 48], "component": "indirect", "prime": false,
      "threads": 1,                             # per task (each worker runs one task at a time)
      "reference": {"method": "pt", "spp": 16, "tile": 16, "seed": null, "verify": false},
      "retries": 2
    }

A scene's "script" defaults to the scene file's own; "" means none. reference.verify also
renders each reference in one task and checks the merge against it (bit-exact).
"""
import copy
import csv
import json
import logging
import os
import subprocess
import sys
import time
import uuid

import numpy as np

DEFAULTS = {
    "methods": ["iim"],
    "settings": {"default": {}},
    "seeds": [None],
    "baselines": ["selective"],
    "frames": 60,
    "size": [48, 48],
    "component": "indirect",
    "prime": False,
    "threads": 1,
    "retries": 2,
}
REFERENCE_DEFAULTS = {"method": "pt", "spp": 16, "tile": 16, "seed": None, "verify": False,
                      "photons": 400000}


class SpecError(ValueError):
    """A spec that cannot run; the message names the spec file and the key."""


def _deep_merge(base, extra):
    out = copy.deepcopy(base)
    for k, v in extra.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def load_spec(path):
    """Reads and checks a spec file; scene and script paths become absolute."""
    try:
        with open(path) as f:
            spec = json.load(f)
    except OSError as e:
        raise SpecError(f"{path}: cannot read the spec: {e.strerror}") from None
    except json.JSONDecodeError as e:
        raise SpecError(f"{path}:{e.lineno}:{e.colno}: invalid JSON: {e.msg}") from None
    return normalise_spec(spec, path)


def normalise_spec(spec, path="<spec>"):
    """Fills in defaults, checks types and resolves paths against the spec's folder."""
    if not isinstance(spec, dict):
        raise SpecError(f"{path}: expected a JSON object")
    known = set(DEFAULTS) | {"scenes", "reference", "name"}
    for key in spec:
        if key not in known:
            raise SpecError(f"{path}: /{key}: unknown key (expected one of {', '.join(sorted(known))})")
    out = copy.deepcopy(DEFAULTS)
    out.update({k: copy.deepcopy(v) for k, v in spec.items() if k != "reference"})
    out["reference"] = _deep_merge(REFERENCE_DEFAULTS, spec.get("reference", {}))
    for key in out["reference"]:
        if key not in REFERENCE_DEFAULTS:
            raise SpecError(f"{path}: /reference/{key}: unknown key (expected one of "
                            f"{', '.join(sorted(REFERENCE_DEFAULTS))})")
    base = os.path.dirname(os.path.abspath(path)) if path != "<spec>" else os.getcwd()
    scenes = out.get("scenes")
    if not isinstance(scenes, list) or not scenes:
        raise SpecError(f"{path}: /scenes: expected a non-empty list of scene files")
    resolved = []
    for i, s in enumerate(scenes):
        s = {"path": s} if isinstance(s, str) else dict(s)
        if not isinstance(s.get("path"), str):
            raise SpecError(f"{path}: /scenes/{i}/path: expected a scene file path")
        s["path"] = os.path.normpath(os.path.join(base, s["path"]))
        if not os.path.isfile(s["path"]):
            raise SpecError(f"{path}: /scenes/{i}/path: no such file: {s['path']}")
        if s.get("script"):
            s["script"] = os.path.normpath(os.path.join(base, s["script"]))
        s.setdefault("name", os.path.splitext(os.path.basename(s["path"]))[0])
        resolved.append(s)
    names = [s["name"] for s in resolved]
    if len(set(names)) != len(names):
        raise SpecError(f"{path}: /scenes: scene names must differ (give \"name\"): {names}")
    out["scenes"] = resolved
    if not isinstance(out["settings"], dict) or not out["settings"]:
        raise SpecError(f"{path}: /settings: expected an object of named settings")
    for key in ("methods", "seeds", "baselines"):
        if not isinstance(out[key], list) or not out[key]:
            raise SpecError(f"{path}: /{key}: expected a non-empty list")
    size = out["size"]
    if not (isinstance(size, list) and len(size) == 2 and all(isinstance(v, int) and v > 0
                                                               for v in size)):
        raise SpecError(f"{path}: /size: expected [width, height], got {size!r}")
    if not isinstance(out["reference"]["tile"], int) or out["reference"]["tile"] < 1:
        raise SpecError(f"{path}: /reference/tile: expected a tile size >= 1")
    return out


# ---- tasks (they run on the workers; each loads what it needs from files) ---------------------

def _final_state(scene_spec, frames):
    import afterglow
    scene = afterglow.Scene.load(scene_spec["path"])
    script = scene_spec.get("script", scene.script)
    if script:
        scene.run_script(script, frames)
    return scene


def reference_tile(scene_spec, frames, size, reference, threads, region):
    """One region of a scene's reference (the state at the end of its script)."""
    import afterglow
    t0 = time.time()
    scene = _final_state(scene_spec, frames)
    kw = dict(method=reference["method"], spp=reference["spp"], seed=reference["seed"],
              threads=threads, size=tuple(size), region=tuple(region))
    if reference["method"] == "pm":
        kw.update(photons=reference["photons"], caustic_photons=reference["photons"])
    result = afterglow.render_reference(scene, **kw)
    return {"region": tuple(region), "images": {c: result[c] for c in afterglow.components},
            "seconds": time.time() - t0}


def merge_reference(size, *tiles):
    import afterglow
    return afterglow.merge_tiles([(t["region"], t["images"]) for t in tiles], size[0], size[1])


def convergence_run(scene_spec, method, settings_name, settings, seed, baseline, spec, reference):
    """One convergence run against the merged reference; returns its table and settle analysis."""
    import afterglow
    t0 = time.time()
    scene = afterglow.Scene.load(scene_spec["path"])
    run_settings = _deep_merge(settings, {"indirect": {"method": method}})
    if seed is not None:
        run_settings["seed"] = seed
    script = scene_spec.get("script")
    result = afterglow.converge(
        scene, script=script, frames=spec["frames"], size=tuple(spec["size"]),
        component=spec["component"], baseline=baseline,
        reference=reference[spec["component"]], threads=spec["threads"], prime=spec["prime"],
        settings=run_settings)
    result["seconds"] = time.time() - t0
    return result


ATTEMPT_EVENTS = "afterglow-sweep-attempt"


def _task(fn, *args):
    """Runs one sweep task, first logging the attempt on the scheduler (the sweep counts a task's
    attempts from these, retries included)."""
    try:
        from distributed import get_worker
        worker = get_worker()
    except ValueError:  # not on a Dask worker
        return fn(*args)
    worker.log_event(ATTEMPT_EVENTS, worker.get_current_task())
    return fn(*args)


# ---- the sweep ------------------------------------------------------------------------------------

def _plot_script():
    here = os.path.dirname(os.path.abspath(__file__))
    for candidate in (os.environ.get("AFTERGLOW_PLOT_SCRIPT", ""),
                      os.path.join(here, "..", "..", "..", "tools", "plot_convergence.py"),
                      os.path.join(here, "..", "..", "plot_convergence.py")):
        if candidate and os.path.isfile(candidate):
            return os.path.abspath(candidate)
    return None


def _log(message):
    print(message, file=sys.stderr, flush=True)


def run(spec, out_dir, client=None, scheduler=None, workers=2, plots=True):
    """Runs a normalised spec (normalise_spec/load_spec) on `client`, else on the scheduler at
    `scheduler` (tcp://HOST:8786), else on a LocalCluster of `workers` processes (one thread
    each). Writes the results under `out_dir`; returns the summary rows (one per task)."""
    from distributed import Client, LocalCluster, as_completed

    own = []
    if client is None:
        if scheduler:
            client = Client(scheduler)
        else:
            # Failures are reported once, by the sweep, not also by each worker's log.
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address=None, silence_logs=logging.ERROR)
            own.append(cluster)
            client = Client(cluster)
        own.insert(0, client)
    try:
        return _run(spec, out_dir, client, as_completed, plots)
    finally:
        for thing in own:
            thing.close()


def _run(spec, out_dir, client, as_completed, plots):
    os.makedirs(os.path.join(out_dir, "references"), exist_ok=True)
    os.makedirs(os.path.join(out_dir, "runs"), exist_ok=True)
    import afterglow
    retries = int(spec["retries"])
    size, frames, ref = spec["size"], spec["frames"], spec["reference"]
    tasks = {}  # key -> (kind, description dict)
    # Dask keys are unique per sweep (a finished key still held by the scheduler would be reused);
    # the names reported are the keys without that suffix.
    token = uuid.uuid4().hex[:8]

    def shown(key):
        return key[:-len(token) - 1]

    futures = []
    references = {}
    verify = {}
    for s in spec["scenes"]:
        tile_futures = []
        for region in afterglow.tiles(size[0], size[1], ref["tile"]):
            key = f"reference-{s['name']}-{region[0]}-{region[1]}-{token}"
            f = client.submit(_task, reference_tile, s, frames, size, ref, spec["threads"], region,
                              key=key, retries=retries, pure=False)
            tasks[key] = ("reference tile", {"scene": s["name"], "region": region})
            tile_futures.append(f)
        key = f"merge-{s['name']}-{token}"
        references[s["name"]] = client.submit(_task, merge_reference, size, *tile_futures, key=key,
                                              retries=retries, pure=False)
        tasks[key] = ("reference merge", {"scene": s["name"]})
        futures += tile_futures + [references[s["name"]]]
        if ref["verify"]:
            key = f"reference-{s['name']}-whole-{token}"
            verify[s["name"]] = client.submit(_task, reference_tile, s, frames, size, ref,
                                              spec["threads"], (0, 0, size[0], size[1]), key=key,
                                              retries=retries, pure=False)
            tasks[key] = ("reference whole", {"scene": s["name"]})
            futures.append(verify[s["name"]])
    runs = {}
    for s in spec["scenes"]:
        for method in spec["methods"]:
            for settings_name, settings in spec["settings"].items():
                for seed in spec["seeds"]:
                    for baseline in spec["baselines"]:
                        key = (f"converge-{s['name']}-{method}-{settings_name}-seed{seed}-"
                               f"{baseline}-{token}")
                        f = client.submit(_task, convergence_run, s, method, settings_name, settings,
                                          seed, baseline, spec, references[s["name"]], key=key,
                                          retries=retries, pure=False)
                        runs[key] = f
                        tasks[key] = ("converge", {"scene": s["name"], "method": method,
                                                   "settings": settings_name, "seed": seed,
                                                   "baseline": baseline})
                        futures.append(f)

    _log(f"sweep: {len(futures)} tasks ({len(runs)} convergence runs, "
         f"{len(futures) - len(runs)} reference tasks) on "
         f"{len(client.scheduler_info()['workers'])} workers, retries {retries}")
    summary = {}
    done = 0
    t0 = time.time()
    for f in as_completed(futures):
        done += 1
        kind, what = tasks[f.key]
        row = {"task": shown(f.key), "kind": kind, **what, "status": f.status, "attempts": 0,
               "error": "", "seconds": ""}
        if f.status == "finished":
            result = f.result()
            if isinstance(result, dict) and "seconds" in result:
                row["seconds"] = f"{result['seconds']:.2f}"
            if kind == "converge":
                row["settled_relmse"] = result["settle"]["settled"]
                row["settle_frame"] = result["settle"]["within"]
                row["settle_s"] = result["settle"]["seconds"]
                row["wall_s"] = result["wall_s"]
            _log(f"[{done}/{len(futures)}] {shown(f.key)}: done"
                 + (f" in {row['seconds']} s" if row["seconds"] else "")
                 + f" ({time.time() - t0:.1f} s into the sweep)")
        else:
            exc = f.exception()
            row["error"] = f"{type(exc).__name__}: {exc}"
            _log(f"[{done}/{len(futures)}] {shown(f.key)}: FAILED (retries {retries}): "
                 f"{row['error']}")
        summary[f.key] = row

    # Attempts per task, as the workers logged them (a log event reaches the scheduler before
    # the task's result does).
    attempts = {}
    for _, key in client.get_events(ATTEMPT_EVENTS):
        attempts[key] = attempts.get(key, 0) + 1
    for key, row in summary.items():
        row["attempts"] = attempts.get(key, 0)
        if row["status"] == "finished" and row["attempts"] > 1:
            _log(f"sweep: {shown(key)} finished after {row['attempts']} attempts")

    # References: exact (.npy) and viewable (.exr, .png); the merge checked against the whole.
    for name, f in references.items():
        if f.status != "finished":
            continue
        merged = f.result()
        for c, image in merged.items():
            stem = os.path.join(out_dir, "references", name + ("" if c == "full" else "." + c))
            np.save(stem + ".npy", image)
            afterglow.write_image(image, stem + ".exr")
        afterglow.write_image(merged["full"], os.path.join(out_dir, "references", name + ".png"))
        if name in verify and verify[name].status == "finished":
            whole = verify[name].result()["images"]
            same = all(np.array_equal(whole[c], merged[c]) for c in merged)
            summary[verify[name].key]["error"] = "" if same else "merged tiles differ"
            summary[verify[name].key]["status"] = "finished" if same else "mismatch"
            _log(f"sweep: reference {name}: merged tiles "
                 + ("equal the whole-image render bit for bit" if same else "DIFFER from the "
                    "whole-image render"))

    # The table: one row per frame of every finished run.
    columns = None
    rows = []
    run_csv = {}
    for key, f in runs.items():
        if f.status != "finished":
            continue
        result = f.result()
        what = tasks[key][1]
        table = result["table"]
        if columns is None:
            columns = ["scene", "method", "settings", "seed", "baseline"] + list(table)
        n = len(table["frame"])
        for i in range(n):
            rows.append([what["scene"], what["method"], what["settings"], what["seed"],
                         what["baseline"]] + [_number(table[c][i]) for c in table])
        label = what["method"] + ("/" + what["baseline"] if len(spec["baselines"]) > 1 else "")
        run_csv[key] = os.path.join(out_dir, "runs", shown(key)[len("converge-"):] + ".csv")
        with open(run_csv[key], "w") as out:
            out.write(result["csv"].replace(result["method"] + ",", label + ",", n))
    if columns:
        _write_table(os.path.join(out_dir, "sweep"), columns, rows)
    summary_rows = list(summary.values())
    _write_summary(os.path.join(out_dir, "summary.csv"), summary_rows)
    if plots:
        _plots(spec, out_dir, run_csv, tasks)
    failed = [r for r in summary_rows if r["status"] != "finished"]
    _log(f"sweep: {len(summary_rows) - len(failed)} of {len(summary_rows)} tasks finished in "
         f"{time.time() - t0:.1f} s; " + (f"{len(failed)} FAILED (see summary.csv)" if failed
                                            else "none failed") + f"; results in {out_dir}")
    return summary_rows


def _number(v):
    v = float(v)
    return int(v) if v.is_integer() else v


def _write_table(stem, columns, rows):
    with open(stem + ".csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(columns)
        w.writerows(rows)
    try:
        import pyarrow
        import pyarrow.parquet
    except ImportError:
        return
    table = pyarrow.table({c: [r[i] for r in rows] for i, c in enumerate(columns)})
    pyarrow.parquet.write_table(table, stem + ".parquet")


SUMMARY_COLUMNS = ["task", "kind", "scene", "method", "settings", "seed", "baseline", "region",
                   "status", "attempts", "error", "seconds", "wall_s", "settled_relmse",
                   "settle_frame", "settle_s"]


def _write_summary(path, rows):
    keys = SUMMARY_COLUMNS + [k for r in rows for k in r if k not in SUMMARY_COLUMNS]
    keys = list(dict.fromkeys(keys))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, restval="")
        w.writeheader()
        w.writerows(rows)


def _plots(spec, out_dir, run_csv, tasks):
    """One plot per scene, settings and seed: every method (and baseline) against time."""
    script = _plot_script()
    if script is None:
        _log("sweep: warning: tools/plot_convergence.py not found; no plots "
             "(set AFTERGLOW_PLOT_SCRIPT)")
        return
    os.makedirs(os.path.join(out_dir, "plots"), exist_ok=True)
    groups = {}
    for key, path in run_csv.items():
        w = tasks[key][1]
        groups.setdefault((w["scene"], w["settings"], w["seed"]), []).append(path)
    for (scene, settings, seed), csvs in sorted(groups.items(), key=str):
        png = os.path.join(out_dir, "plots", f"{scene}.{settings}.seed{seed}.png")
        title = f"{scene} ({settings}, seed {seed}): {spec['component']} relMSE against time"
        r = subprocess.run([sys.executable, script, png, *csvs, "--title", title],
                           capture_output=True, text=True)
        if r.returncode != 0:
            _log(f"sweep: warning: plotting {png} failed: {r.stderr.strip()}")


def main(argv=None):
    import argparse
    p = argparse.ArgumentParser(
        prog="tools/sweep",
        description="Run a grid of convergence runs and tiled reference renders as Dask tasks "
                    "(docs/python.md).")
    p.add_argument("spec", help="the sweep spec (JSON)")
    p.add_argument("-o", "--out", help="results folder (default out/sweep-SPECNAME)")
    p.add_argument("--scheduler", help="an existing Dask scheduler, tcp://HOST:8786 "
                                       "(default: a LocalCluster on this machine)")
    p.add_argument("--workers", type=int, default=2,
                   help="LocalCluster worker processes (default 2)")
    p.add_argument("--no-plots", action="store_true", help="skip the plots")
    args = p.parse_args(argv)
    try:
        spec = load_spec(args.spec)
    except SpecError as e:
        print(f"tools/sweep: error: {e}", file=sys.stderr)
        return 1
    out = args.out or os.path.join("out", "sweep-" + os.path.splitext(os.path.basename(args.spec))[0])
    if args.workers < 1:
        print("tools/sweep: error: --workers expects a count >= 1", file=sys.stderr)
        return 2
    try:
        rows = run(spec, out, scheduler=args.scheduler, workers=args.workers,
                   plots=not args.no_plots)
    except OSError as e:  # includes the timeout of an unreachable scheduler
        where = f"the scheduler at {args.scheduler}" if args.scheduler else "the LocalCluster"
        print(f"tools/sweep: error: cannot reach {where}: {e}", file=sys.stderr)
        return 1
    return 1 if any(r["status"] != "finished" for r in rows) else 0
