"""3. `aurora render` against Cycles at equal error against a converged
reference: per case the reference, both renderers' ladders of sample
counts (alternating rung by rung), the samples and times to reach the
target errors, and the dome master's own bake."""

from __future__ import annotations

import itertools
from pathlib import Path

from metrics import (case_error, downsample, equal_error_ratios, fisheye_mask, interpolate, lowest_rung,
                     rung_summary)
from runners import CyclesWorker, Tools, aurora_render, bake, log
from scenes import case_scene, dome_scene, reference_scene
from settings import ADAPTIVE_THRESHOLD, KNOWN_BIAS, REF_SEEDS, SHADOW_SAMPLES, STEP_RATE, THREADS, WHOS


def study_render(tools: Tools, cfg: dict, worker: CyclesWorker, scene_text: str, vdb: Path, out: Path,
                 targets: dict) -> dict:
    w, h = cfg["size"]
    d = out / "render"
    d.mkdir(parents=True, exist_ok=True)
    res = {"blender": worker.info["blender"], "size": [w, h], "threads": THREADS, "cases": {}}
    cases = cfg.get("cases", ("volume", "terrain"))
    padded = d / "aurora.cycles-padded.vdb"
    res["cycles_padding_s"] = 0.0
    if any(c != "dome" for c in cases):
        pad = worker.ask(op="pad", src=str(vdb), dst=str(padded))
        res["cycles_padding_s"] = pad["seconds"]
    for case in cases:
        if case == "dome":
            res["cases"][case] = dome_case(tools, cfg, worker, d / case, targets[case])
            res["cycles_padding_s"] += res["cases"][case]["bake"]["cycles_padding_s"]
            continue
        res["cases"][case] = render_case(tools, cfg, worker, scene_text, vdb, padded, d / case, case, targets[case])
    return res


def dome_case(tools: Tools, cfg: dict, worker: CyclesWorker, d: Path, target: float) -> dict:
    """The DOME preset at its size, baked for that camera, then render_case."""
    dome = cfg["dome"]
    w, h = dome["size"]
    d.mkdir(parents=True, exist_ok=True)
    text, scene = dome_scene(tools, dome, d)
    log(f"render dome: bake {dome['preset']} at {w}x{h}")
    b = bake(tools, scene, d / "bake")
    vdb = d / "bake" / "aurora.vdb"
    padded = d / "aurora.cycles-padded.vdb"
    pad = worker.ask(op="pad", src=str(vdb), dst=str(padded))
    # One run per rung: a 1024x1024 Cycles rung takes minutes.
    res = render_case(tools, {**cfg, "size": (w, h), "ref_factor": 1, "bracket_repeats": 0,
                              "ref_spp_dome": dome["ref_spp"]}, worker, text, vdb, padded, d, "dome", target)
    res["bake"] = {"preset": dome["preset"], "edits": {f"{k[0]}.{k[1]}": v for k, v in dome["scene_edits"].items()},
                   "wall_s": b["wall_s"], "cpu_s": b["cpu_s"], "times_s": b["bake"]["stats"]["times_s"],
                   "active_voxels": b["bake"]["stats"]["active_voxels"], "cycles_padding_s": pad["seconds"]}
    return res


def render_case(tools: Tools, cfg: dict, worker: CyclesWorker, scene_text: str, vdb: Path, padded: Path, d: Path,
                case: str, target: float) -> dict:
    import numpy as np

    w, h = cfg["size"]
    d.mkdir(parents=True, exist_ok=True)
    scene = case_scene(scene_text, case, w, h, d)
    shadow = SHADOW_SAMPLES[case]
    step = STEP_RATE[case]

    mask = None
    if case == "terrain":
        mpath = d / "terrain-mask.npy"
        worker.ask(op="terrain_mask", scene=str(scene), width=w, height=h, out=str(mpath))
        mask = np.load(mpath)
    elif case == "dome":
        mask = fisheye_mask(w, h)

    ref, reference = make_reference(tools, cfg, scene, vdb, d, case, mask)

    # Warm-up (untimed): page cache, Cycles kernels.
    aurora_render(tools, scene, vdb, d / "warmup-aurora.exr", 2, shadow)
    worker.ask(op="render", scene=str(scene), vdb=str(padded), out=str(d / "warmup-cycles.exr"), samples=1,
               threads=THREADS, step_rate=step)

    stat = cfg["stat"]
    targets = [target] + [t for t in cfg["extra_targets"].get(case, []) if t != target]
    ladders = run_ladders(tools, cfg, worker, scene, vdb, padded, d, case, target, ref, mask)
    eq_all = {t: {who: interpolate(ladders[who], t, stat) for who in ladders} for t in targets}
    eq = eq_all[target]

    ratios = equal_error_ratios(eq)
    for t in targets[1:]:
        for k, v in equal_error_ratios(eq_all[t]).items():
            ratios[f"at_{100 * t:g}pct.{k}"] = v
    low = lowest_rung(ladders, stat)
    if case == "dome":
        # aurora's first rung already beats any target Cycles' ladder reaches
        # in the time at hand: the dome's figure is Cycles' time to aurora's
        # error at that rung, measured if Cycles reached it, else a bound
        # (nothing extrapolated).
        ratios = dict(low["ratios"])
    top = ladders["cycles"][-1]
    agree_tol = KNOWN_BIAS[case] + 0.01
    return {
        "scene": str(scene),
        "size": [w, h],
        "what": {
            "aurora": f"aurora render --spp N --shadow-samples {shadow} --threads {THREADS}: stratified antithetic "
                      "positions in the pixel square (render::pixel_position: Sobol (0,2) points and their "
                      "reflections through the centre); time = wall of the process (read VDB, build, render, "
                      "write EXR)",
            "cycles": f"tools/cycles/cycles_render.render, Cycles CPU, {THREADS} threads, biased volume mode, step rate "
                      f"{step}, box filter, padded VDB{', terrain lit by emission point lights' if case == 'terrain' else ''}; "
                      "time = wall of bpy.ops.render.render in one bpy process (set-up excluded, in setup_s)",
            "metric": "mean relative error over pixels above 1% of the peak (tools/cycles/compare.py)"
                      + ("; over the pixels wholly on the plane" if case == "terrain" else "")
                      + ("; RGB and alpha over the pixels wholly inside the fisheye's image circle"
                         if case == "dome" else ""),
        },
        "shadow_samples": shadow,
        "step_rate": step,
        "reference": reference,
        "ladders": ladders,
        "cycles_adaptive_threshold": ADAPTIVE_THRESHOLD if "cycles_adaptive" in ladders else None,
        "stat": stat,
        "bracket_runs": 1 + cfg["bracket_repeats"],
        "target_error": target,
        "equal_error": eq,
        "targets": [{"target_error": t, "equal_error": eq_all[t], "ratios": equal_error_ratios(eq_all[t])}
                    for t in targets],
        "ratios": ratios,
        "at_aurora_lowest_rung": low,
        "cycles_converged": {
            "samples": top["samples"], "error": top["error"], "flux_ratio": top["flux_ratio"],
            "known_cross_check_bias": KNOWN_BIAS[case],
            "agrees": abs(top["flux_ratio"] - 1.0) <= agree_tol,
            "rule": f"|Cycles flux / reference flux - 1| <= known bias + 1% = {agree_tol:.4f}",
        },
    }


def make_reference(tools: Tools, cfg: dict, scene: Path, vdb: Path, d: Path, case: str, mask):
    """The reference image, `aurora render` at two seeds (independent of the
    ladders' seed) averaged, and what the report says of it."""
    import numpy as np

    from aurora_tools import image_compare as compare
    from aurora_tools.exr_io import write_rgba_exr

    w, h = cfg["size"]
    shadow = SHADOW_SAMPLES[case]
    log(f"render {case}: reference")
    refs, ref_runs = [], []
    f = cfg["ref_factor"] if case == "volume" else 1
    ref_scene = reference_scene(scene, w, h, f, d)
    spp_ref = cfg[f"ref_spp_{case}"]
    for s in REF_SEEDS:
        p = d / f"reference-seed{s}.exr"
        ref_runs.append(aurora_render(tools, ref_scene, vdb, p, spp_ref, shadow, seed=s))
        img = compare.read_rgba(p)
        refs.append(downsample(img, f) if f > 1 else img)
    ref = 0.5 * (refs[0] + refs[1])
    write_rgba_exr(d / "reference.exr", ref.astype(np.float32), {"aurora_reference": f"mean of seeds {REF_SEEDS}"})
    mutual = compare.metrics(refs[0], refs[1], mask)
    mutual_err = mutual["mask_mean_rel_err"] if mask is not None else mutual["mean_rel_err"]
    reference = {
        "renderer": "aurora render",
        "why": "exact ray integration (closed-form tests to 1e-4): its only error is Monte Carlo noise, which "
               "averages away; Cycles' biased ray marching has a step bias and its terrain lights are clustered",
        "seeds": list(REF_SEEDS), "spp_per_seed": spp_ref, "shadow_samples": shadow,
        "subpixels": f"{f}x{f}" if f > 1 else "1",
        "samples_per_pixel_total": 2 * spp_ref * f * f,
        "runs": ref_runs,
        "seed_to_seed_error": mutual_err,
        # Two independent halves differ by sqrt(2) sigma; their mean is off by
        # sigma / sqrt(2): half their difference, in the same metric.
        "own_error_estimate": mutual_err / 2,
    }
    return ref, reference


def run_ladders(tools: Tools, cfg: dict, worker: CyclesWorker, scene: Path, vdb: Path, padded: Path, d: Path,
                case: str, target: float, ref, mask) -> dict:
    """Every renderer's ladder of sample counts, alternating rung by rung,
    then the rungs that bracket the headline target again (bracket_repeats
    times): each renderer's rungs, with their errors and times."""
    shadow = SHADOW_SAMPLES[case]
    step = STEP_RATE[case]
    lad = cfg["ladder"][case]
    whos = [w for w in WHOS if lad.get(w)]
    rungs = {w: {} for w in whos}
    stat = cfg["stat"]

    def do(who: str, n: int) -> None:
        if who in ("aurora", "aurora_adaptive"):
            adaptive = who == "aurora_adaptive"
            p = d / f"{'aurora-adaptive' if adaptive else 'aurora'}-{n:05d}.exr"
            r = aurora_render(tools, scene, vdb, p, n, shadow, adaptive=adaptive)
            t = {"wall_s": r["wall_s"], "cpu_s": r["cpu_s"], "pixel_loop_s": r["pixel_loop_s"]}
        else:
            adaptive = who == "cycles_adaptive"
            p = d / f"{'cycles-adaptive' if adaptive else 'cycles'}-{n:05d}.exr"
            r = worker.ask(op="render", scene=str(scene), vdb=str(padded), out=str(p), samples=n, threads=THREADS,
                           step_rate=step, adaptive=ADAPTIVE_THRESHOLD if adaptive else None)
            t = {"wall_s": r["render_s"], "cpu_s": r["render_cpu_s"], "setup_s": r["setup_s"]}
        e = rungs[who].setdefault(n, {"samples": n, "runs": [], **case_error(case, p, ref, mask)})
        e["runs"].append(t)

    order = list(itertools.zip_longest(*(lad[w] for w in whos)))
    for row in order:  # alternate the renderers rung by rung
        for who, n in zip(whos, row):
            if n is not None:
                log(f"render {case}: {who} {n} samples")
                do(who, n)

    eq = {who: interpolate(rung_summary(rungs[who]), target, stat) for who in rungs}
    # Re-time the bracketing rungs of the headline target (alternating).
    for _ in range(cfg["bracket_repeats"]):
        for i in range(2):
            for who in whos:
                n = eq[who]["between"][i]
                log(f"render {case}: {who} {n} again (brackets the target)")
                do(who, n)
    return {who: rung_summary(rungs[who]) for who in rungs}
