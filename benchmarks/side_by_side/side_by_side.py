#!/usr/bin/env python3
"""Side by side, in one run, on one machine: aurora against the reference tools.

    .venv/bin/python benchmarks/side_by_side/side_by_side.py [--out DIR] [--quick] [--skip-seed2014]
        [--volume-target E] [--terrain-target E] [--size WxH] [--cases volume,terrain,dome]
        [--render-only] [--repeats N]

Four studies, every number into DIR/side_by_side.json and a
table into DIR/side_by_side.txt and stdout (default DIR: target/side-by-side/):

1. VDB writer. `aurora bake default` once; then, best of N runs with the
   writers alternating, on that bake's grids (f32): our writer (timed by
   examples/vdb_write_bench.rs, which also times OpenVDB's C++ writer,
   benchmarks/vdb_write/openvdb_write_bench.cpp, both ZIP + active mask,
   the C++ side with grid class "unknown" because OpenVDB's Archive drops
   ZIP for fog volumes),
   pyopenvdb's `write` (it exposes no compression setting: it writes io::File's
   default, Blosc + active mask) and the C++ writer again with Blosc + active
   mask (pyopenvdb's flags). The files each writer wrote are read back with
   pyopenvdb and must hold identical active voxels and values, else the run
   fails.
2. Gather. The same scene baked with `[photons] gather` = "kdtree",
   "splat" (the default) and "report2014" (the report's uniform-grid lookup: an average
   colour, not a density; same stage, different estimator); `times_s.gather`
   from each bake.json, best of N.
3. `aurora render` against Cycles (CPU, through the add-on,
   tools/cycles/cycles_render.py) at equal error against a converged reference, as the
   Cycles cross-check sets them up (tests/python/test_cross_check.py): the
   default bake at 160x90, volume only and a plane lit by the aurora; both
   average over the pixel square (box filter; aurora's samples are its
   stratified antithetic set, Cycles' its own sequence; [render]
   spp > 1 in the scene file); 2 threads each. Reference: `aurora render`
   itself (exact ray integration; the only noise is pixel and shadow
   sampling), two independent seeds averaged; the volume's rendered at 8x8
   sub-pixels (stratified pixel area) and block-averaged. Each renderer runs
   a ladder of sample counts; error = mean relative error over bright pixels
   (tools/cycles/compare.py; terrain: over the pixels wholly on the plane).
   The time to reach the target error is interpolated log-log between the two rungs
   that bracket it (their times: best of 2 in the full run; --repeats N runs
   them N times, and from 3 on the median is used). The volume case also
   reports the 0.5 % crossing (one run per rung) and Cycles with its adaptive
   sampling on (noise threshold 0.01, Blender's default) beside the headline
   Cycles with adaptive sampling off, and `aurora render --adaptive` (its
   adaptive sampling by pixel variance) against both. Aurora's ladder has
   rungs 6, 8 and 12 so that its 2 % crossing is measured, not interpolated
   across 4..16; --ladder WHO=N,N,... replaces one volume ladder (to fit a
   run in the time at hand: keep the rungs that bracket the targets). --size 640x360 runs the volume case
   at 640x360 with its own ladders and a 1x1 sub-pixel reference (SIZE_640);
   --render-only skips the VDB writer, gather and seed2014 studies.
   --cases dome (not in the default cases) adds a dome master: the `oval`
   preset's own camera (180-degree equidistant fisheye looking up) at
   1024x1024 (DOME), baked for it, without its stars and airglow;
   reference aurora render at 32 spp x 2 seeds at the image's own pixels;
   errors (RGB, and alpha) over the pixels
   wholly inside the image circle, since outside it aurora's alpha is 0 (no
   ray) and Cycles' 1; one run per rung. Its figure is Cycles against
   aurora's lowest rung: Cycles' time to that rung's error, interpolated
   between its bracketing rungs, or a bound (">=": Cycles' last rung has not
   reached it) when its ladder does not bracket it; nothing is extrapolated.
   Times: `aurora render` = wall time of the whole process (read the VDB,
   build, render, write the EXR); Cycles = wall time of bpy.ops.render.render
   inside one long-lived bpy process (Cycles' sync, loading the VDB, sampling,
   writing the EXR), measured in bpy; Blender's start-up, the add-on's scene
   set-up (camera, material, the terrain's emission point lights) and the
   one-off padding of the VDB are left out and reported apart. Process CPU
   times (user + system) are reported too: on a shared machine they are less
   sensitive to other jobs.
4. `aurora bake seed2014` under /usr/bin/time -v: wall time, peak RSS and the
   stage split from bake.json (skip with --skip-seed2014; --quick skips it).

Ratios are ours / theirs (< 1: aurora is faster or smaller). --quick: a
reduced scene (1,000 beams, 1 km voxels), 64x36 pixels, short ladders, one run each, no
seed2014 (tests/python/test_side_by_side.py).

Needs target/release/aurora (AURORA_BIN overrides), cargo (builds
examples/vdb_write_bench), g++ and libopenvdb (the C++ writer), pyopenvdb,
numpy, OpenEXR, and bpy for the Cycles worker (this same interpreter).
Standard library otherwise. Outputs are written to a temporary name and
renamed. Any missing tool or failed check exits non-zero with a message.

This file is the command line and the order of the run; beside it:
settings.py (what each mode runs), scenes.py (the scene files),
runners.py (commands, aurora, the Cycles worker, machine facts),
metrics.py (errors, equal-error interpolation, ratios), bake_studies.py
(studies 1, 2 and 4), render_study.py (study 3) and report.py (the table).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import re
import sys
import time
from pathlib import Path

# OpenVDB's io::File otherwise maps the file and loads leaf buffers on first
# touch, which would put reading inside the timed pyopenvdb write. Read once,
# at import of pyopenvdb's File, so set it before anything imports it.
os.environ["OPENVDB_DISABLE_DELAYED_LOAD"] = "1"

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))  # the shared package aurora_tools
from aurora_tools import ROOT  # noqa: E402
from aurora_tools.files import write_atomic  # noqa: E402
from bake_studies import study_gather, study_seed2014, study_vdb  # noqa: E402
from render_study import study_render  # noqa: E402
from report import all_ratios, report_text  # noqa: E402
from runners import (CyclesWorker, Failure, Tools, bake, git_facts, import_pyopenvdb, load, log,  # noqa: E402
                     machine_facts, worker_main)
from scenes import default_scene, f32_scene  # noqa: E402
from settings import CASES, FULL, QUICK, SIZE_640, WHOS  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default=str(ROOT / "target" / "side-by-side"), help="output folder")
    p.add_argument("--quick", action="store_true", help="reduced scene, tiny images, one run each, no seed2014")
    p.add_argument("--skip-seed2014", action="store_true", help="skip the seed2014 bake (about 5 minutes)")
    p.add_argument("--volume-target", type=float, help="target error, volume only (default 0.02; quick 0.2)")
    p.add_argument("--terrain-target", type=float, help="target error, terrain (default 0.05; quick 0.1)")
    p.add_argument("--size", help="render study image size WxH (default 160x90; 640x360 selects its own ladders, "
                                  "reference and one run per rung: SIZE_640)")
    p.add_argument("--cases", default="volume,terrain", help="render study cases (comma-separated: volume, terrain, "
                                                             "dome: the oval preset's 1024x1024 dome master)")
    p.add_argument("--render-only", action="store_true", help="bake, then only the render study (no VDB writer, "
                                                                "gather or seed2014 study)")
    p.add_argument("--repeats", type=int, help="runs of the rungs that bracket the headline target (default 2; "
                                               "3 or more: equal-error times from the median of the runs, else the best)")
    p.add_argument("--ladder", action="append", default=[], metavar="WHO=N,N,...",
                   help="replace one volume ladder (WHO: " + ", ".join(WHOS) + "; empty list drops it), e.g. to "
                        "fit a run in the time at hand: the rungs that bracket the targets")
    p.add_argument("--cycles-worker", type=int, help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.cycles_worker is not None:
        return worker_main(a.cycles_worker)
    for t in (a.volume_target, a.terrain_target):
        if t is not None and not 0 < t < 1:
            p.error("target errors must lie in (0, 1)")
    try:
        return run_all(a)
    except Failure as e:
        print(f"side_by_side: error: {e}", file=sys.stderr)
        return 1


def require_modules() -> None:
    """Fail at once, with a message, if a module the run needs is missing."""
    for name, why in (("numpy", "images and metrics"), ("OpenEXR", "reading and writing EXR images")):
        try:
            __import__(name)
        except ImportError as e:
            raise Failure(f"cannot import {name} ({why}); run with .venv/bin/python (tools/setup): {e}") from e
    import_pyopenvdb()


def run_all(a) -> int:
    cfg = dict(QUICK if a.quick else FULL)
    if a.size:
        m = re.fullmatch(r"(\d+)x(\d+)", a.size)
        if not m:
            raise Failure(f"--size {a.size}: expected WxH, e.g. 640x360")
        size = (int(m.group(1)), int(m.group(2)))
        cfg.update(SIZE_640 if size == SIZE_640["size"] else {"size": size})
    for spec in a.ladder:
        who, _, ns = spec.partition("=")
        if who not in WHOS or not re.fullmatch(r"(\d+(,\d+)*)?", ns):
            raise Failure(f"--ladder {spec}: expected WHO=N,N,... with WHO one of {', '.join(WHOS)}")
        lad = {**cfg["ladder"], "volume": dict(cfg["ladder"]["volume"])}
        lad["volume"][who] = [int(x) for x in ns.split(",") if x]
        cfg["ladder"] = lad
    cases = tuple(c for c in a.cases.split(",") if c)
    if not cases or any(c not in CASES for c in cases):
        raise Failure(f"--cases {a.cases}: expected some of {', '.join(CASES)}")
    cfg["cases"] = cases
    if a.repeats is not None:
        if a.repeats < 1:
            raise Failure("--repeats must be at least 1")
        cfg["bracket_repeats"] = a.repeats - 1
    cfg["stat"] = "median" if cfg["bracket_repeats"] >= 2 else "best"
    require_modules()
    out = Path(a.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    res = {
        "schema": 1,
        "mode": "quick" if a.quick else "full",
        "options": {"size": list(cfg["size"]), "cases": list(cfg["cases"]), "render_only": a.render_only,
                    "bracket_runs": 1 + cfg["bracket_repeats"], "stat": cfg["stat"]},
        "started_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S"),
        "load_start": load(),
        "machine": machine_facts(),
        "git": git_facts(),
    }
    tools = Tools()
    vdb = import_pyopenvdb()
    # Start bpy first: a missing Blender fails the run before anything is
    # timed, and the worker then waits on its stdin (no CPU) until the renders.
    log("starting the Cycles worker (bpy)")
    (out / "render").mkdir(parents=True, exist_ok=True)
    worker = CyclesWorker(out / "render" / "cycles-worker.log")
    try:
        return run_studies(a, cfg, out, res, tools, vdb, worker, t_start)
    finally:
        worker.close()


def run_studies(a, cfg, out, res, tools, vdb, worker, t_start) -> int:
    res["aurora_version"] = tools.version()
    res["openvdb_version"] = ".".join(map(str, vdb.LIBRARY_VERSION))
    res["sections_s"] = {}

    # The scene: the default preset (quick: fewer beams).
    scene_text, scene_arg = default_scene(tools, cfg, out)
    res["scene"] = {"preset": "default", "edits": {f"{s}.{k}": v for (s, k), v in cfg["scene_edits"].items()}}

    t = time.perf_counter()
    if a.render_only and set(cfg["cases"]) == {"dome"}:
        res["bake"] = {"skipped": "only the dome case, which bakes its own scene"}
    else:
        log(f"bake {scene_arg}")
        main_bake = bake(tools, scene_arg, out / "bake")
        res["bake"] = {"wall_s": main_bake["wall_s"], "times_s": main_bake["bake"]["stats"]["times_s"],
                       "photons": main_bake["bake"]["stats"]["photons"],
                       "active_voxels": main_bake["bake"]["stats"]["active_voxels"],
                       "vdb_bytes": main_bake["bake"]["files"]["vdb_bytes"]}

    if not a.render_only:
        bake(tools, f32_scene(scene_text, out), out / "bake-f32")
        res["vdb_write"] = study_vdb(tools, cfg, out / "bake-f32", out)
        res["sections_s"]["vdb_write"] = time.perf_counter() - t
        t = time.perf_counter()
        res["gather"] = study_gather(tools, cfg, scene_text, main_bake, out)
        res["sections_s"]["gather"] = time.perf_counter() - t
    t = time.perf_counter()
    targets = {"volume": a.volume_target or cfg["target"]["volume"],
               "terrain": a.terrain_target or cfg["target"]["terrain"], "dome": cfg["target"]["dome"]}
    res["render"] = study_render(tools, cfg, worker, scene_text, out / "bake" / "aurora.vdb", out, targets)
    res["sections_s"]["render"] = time.perf_counter() - t
    worker.close()  # free bpy's memory before seed2014
    if a.quick or a.skip_seed2014 or a.render_only:
        res["seed2014"] = {"skipped": True,
                           "why": "--quick" if a.quick else "--render-only" if a.render_only else "--skip-seed2014"}
    else:
        t = time.perf_counter()
        res["seed2014"] = study_seed2014(tools, out)
        res["sections_s"]["seed2014"] = time.perf_counter() - t
    res["ratios"] = all_ratios(res)
    res["load_end"] = load()
    res["finished_utc"] = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S")
    res["wall_s"] = time.perf_counter() - t_start
    bad = {k: v for k, v in res["ratios"].items() if not (math.isfinite(v) and v > 0)}
    text = report_text(res)
    write_atomic(out / "side_by_side.json", (json.dumps(res, indent=2) + "\n").encode())
    write_atomic(out / "side_by_side.txt", text.encode())
    sys.stdout.write(text)
    if bad:
        raise Failure(f"ratios not finite and positive: {bad}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
