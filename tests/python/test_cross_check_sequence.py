"""The Cycles cross-check on two frames of a sequence: the default scene baked
with `--frames 1,25` (one second apart) at 160x90, each frame rendered by
`aurora render --frame N` and by Cycles through the add-on from the frame
file (which the add-on imports as a sequence, showing that file's frame),
volume only, with test_cross_check.py's tolerances: mean relative error over
pixels brighter than 1% of the peak <= 2%, flux within 1%, alpha within 0.01.
The two frames must differ (the curtains move). Images are kept under
target/cross-check/sequence/.
"""

from __future__ import annotations

import json
import sys

import numpy as np

import synth
from test_cross_check import (AURORA_SHADOW, AURORA_SPP, CYCLES_SAMPLES, HEIGHT, OUT, ROOT, STEP_RATE, WIDTH,
                              aurora_bin, default_scene, run)


def test_cycles_matches_aurora_render_on_two_frames_of_a_sequence(compare):
    binary = aurora_bin()
    d = OUT / "sequence"
    d.mkdir(parents=True, exist_ok=True)
    doc = default_scene(binary)
    doc.setdefault("render", {}).update({"width": WIDTH, "height": HEIGHT, "spp": AURORA_SPP["volume"]})
    doc["terrain"] = {**doc.get("terrain", {}), "kind": "none"}
    scene = d / "scene.toml"
    scene.write_text(synth.toml_dumps(doc))
    shot = d / "shot"
    # The folder is kept between runs: --rebake replaces frames of another
    # build or scene, and keeps those of this bake.
    run([binary, "bake", scene, "--frames", "1,25", "--out", shot, "--rebake", "-q"])
    images = {}
    for f in (1, 25):
        vdb = shot / f"aurora.{f:04d}.vdb"
        a, b = d / f"aurora.{f:04d}.exr", d / f"cycles.{f:04d}.exr"
        run([binary, "render", scene, "--vdb", shot, "--frame", str(f), "--out", d / "aurora.exr",
             "--spp", AURORA_SPP["volume"], "--shadow-samples", AURORA_SHADOW["volume"], "-q"])
        run([sys.executable, ROOT / "tools" / "cycles" / "cycles_render.py", scene, "--vdb", vdb, "--out", b,
             "--samples", CYCLES_SAMPLES["volume"], "--step-rate", STEP_RATE["volume"]])
        m = compare.compare(a, b, d / f"diff.{f:04d}.png", d / f"figures.{f:04d}.json")
        print(f"frame {f}:", json.dumps(m))
        assert m["mean_rel_err"] <= 0.02, (f, m)
        assert abs(m["flux_ratio"] - 1.0) <= 0.01, (f, m)
        assert m["max_alpha_diff"] <= 0.01, (f, m)
        images[f] = compare.read_rgba(b)
    # Cycles rendered two different frames (not frame 1 twice).
    assert not np.array_equal(images[1], images[25])
