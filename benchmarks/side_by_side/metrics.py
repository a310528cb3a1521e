"""How the studies measure: a render's error against the reference, the
figures of a ladder's rungs, the samples and time to reach a target error
(interpolated between the rungs that bracket it), and the ratios of the
renderers' times there."""

from __future__ import annotations

import math
import statistics


def best(xs) -> float:
    return min(xs)


def downsample(img, f: int):
    h, w, c = img.shape
    return img.reshape(h // f, f, w // f, f, c).mean(axis=(1, 3))


def fisheye_mask(width: int, height: int) -> "np.ndarray":
    """Pixels of an equidistant fisheye wholly inside its image circle (all
    four corners within it: src/geometry/camera.rs maps the raster to u, v in [-1, 1]
    per axis and has no ray beyond r = 1)."""
    import numpy as np

    ys, xs = np.mgrid[0:height, 0:width]
    inside = np.ones((height, width), bool)
    for dx, dy in ((0, 0), (1, 0), (0, 1), (1, 1)):
        u = 2.0 * (xs + dx) / width - 1.0
        v = 1.0 - 2.0 * (ys + dy) / height
        inside &= u * u + v * v <= 1.0
    return inside


def case_error(case: str, path, ref, mask) -> dict:
    """The error figures of the render at `path` against the reference:
    over the terrain's pixels (`mask`) for the terrain case, RGB and alpha
    inside the image circle (`mask`) for the dome, over the whole image
    otherwise."""
    import numpy as np

    from aurora_tools import image_compare as compare

    img = compare.read_rgba(path)
    m = compare.metrics(img, ref, mask)
    if case == "terrain":
        return {"error": m["mask_mean_rel_err"], "flux_ratio": m["mask_flux_ratio"],
                "pixels": m["mask_bright_pixels"]}
    if case == "dome":
        # RGB and alpha inside the image circle only: outside it aurora
        # writes alpha 0 (no ray), Cycles alpha 1.
        da = np.abs(img[..., 3] - ref[..., 3])[mask]
        return {"error": m["mask_mean_rel_err"], "flux_ratio": m["mask_flux_ratio"],
                "pixels": m["mask_bright_pixels"], "max_alpha_diff": float(da.max())}
    return {"error": m["mean_rel_err"], "flux_ratio": m["flux_ratio"], "pixels": m["bright_pixels"],
            "max_alpha_diff": m["max_alpha_diff"]}


def rung_summary(rungs: dict) -> list[dict]:
    """A renderer's rungs ({samples: rung}) in order of samples, each with
    the best and the median wall and CPU time of its runs."""
    out = []
    for n in sorted(rungs):
        e = rungs[n]
        e["best_wall_s"] = best(r["wall_s"] for r in e["runs"])
        e["best_cpu_s"] = best(r["cpu_s"] for r in e["runs"])
        e["median_wall_s"] = statistics.median(r["wall_s"] for r in e["runs"])
        e["median_cpu_s"] = statistics.median(r["cpu_s"] for r in e["runs"])
        out.append(e)
    return out


def interpolate(ladder: list[dict], target: float, stat: str = "best") -> dict:
    """Samples and times to reach `target` error: log-log between the first
    pair of rungs whose errors bracket it. If no pair does, the samples are
    extrapolated along the nearest pair's log-log line and the times taken
    from a straight-line fit t = a + b n over the whole ladder (flagged)."""
    pts = sorted(ladder, key=lambda r: r["samples"])
    pair = None
    for a, b in zip(pts, pts[1:]):
        if a["error"] >= target >= b["error"]:
            pair = (a, b)
            break
    inside = pair is not None
    if not inside:
        pair = (pts[-2], pts[-1]) if target < pts[-1]["error"] else (pts[0], pts[1])
    a, b = pair
    la, lb = math.log(a["error"]), math.log(b["error"])
    u = (math.log(target) - la) / (lb - la) if lb != la else 0.0

    def lerp(x, y):
        return math.exp(math.log(x) + u * (math.log(y) - math.log(x)))

    n = lerp(a["samples"], b["samples"])
    if inside:
        return {"target": target, "how": "interpolated", "between": [a["samples"], b["samples"]], "samples": n,
                "stat": stat, "wall_s": lerp(a[f"{stat}_wall_s"], b[f"{stat}_wall_s"]),
                "cpu_s": lerp(a[f"{stat}_cpu_s"], b[f"{stat}_cpu_s"])}

    def line(key):
        xs = [p["samples"] for p in pts]
        ys = [p[key] for p in pts]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        sxx = sum((x - mx) ** 2 for x in xs)
        slope = max(sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx, 1e-12) if sxx > 0 else 1e-12
        return max(my - slope * mx, 0.0) + slope * n

    return {"target": target, "how": "extrapolated: the ladder does not reach the target",
            "between": [a["samples"], b["samples"]], "samples": n, "stat": stat, "wall_s": line(f"{stat}_wall_s"),
            "cpu_s": line(f"{stat}_cpu_s")}


def equal_error_ratios(e: dict) -> dict:
    """aurora / Cycles, wall and CPU time, at one target error (`e`: each
    renderer's equal-error point)."""
    r = {"aurora_over_cycles_wall": e["aurora"]["wall_s"] / e["cycles"]["wall_s"],
         "aurora_over_cycles_cpu": e["aurora"]["cpu_s"] / e["cycles"]["cpu_s"]}
    if "cycles_adaptive" in e:
        r["aurora_over_cycles_adaptive_wall"] = e["aurora"]["wall_s"] / e["cycles_adaptive"]["wall_s"]
        r["aurora_over_cycles_adaptive_cpu"] = e["aurora"]["cpu_s"] / e["cycles_adaptive"]["cpu_s"]
    # aurora render --adaptive against Cycles without and with its own.
    if "aurora_adaptive" in e:
        for who, key in (("cycles", "cycles"), ("cycles_adaptive", "cycles_adaptive")):
            if who in e:
                r[f"aurora_adaptive_over_{key}_wall"] = e["aurora_adaptive"]["wall_s"] / e[who]["wall_s"]
                r[f"aurora_adaptive_over_{key}_cpu"] = e["aurora_adaptive"]["cpu_s"] / e[who]["cpu_s"]
    return r


def lowest_rung(ladders: dict, stat: str) -> dict:
    """Cycles against aurora's lowest rung (its error e and time t): Cycles'
    time to e interpolated between the two rungs that bracket it; if its
    last rung is still above e, that rung's time is a lower bound on it
    (relation ">="), and if its first rung is already below e, an upper bound
    ("<="). Nothing is extrapolated. The ratios are aurora / Cycles."""
    a = ladders["aurora"][0]
    cyc = ladders["cycles"]
    out = {"aurora": {"samples": a["samples"], "error": a["error"], "wall_s": a[f"{stat}_wall_s"],
                      "cpu_s": a[f"{stat}_cpu_s"]}}
    if cyc[-1]["error"] > a["error"]:
        c, out["relation"] = cyc[-1], ">="
        how = "its last rung, still above aurora's error: Cycles needs at least this"
    elif cyc[0]["error"] <= a["error"]:
        c, out["relation"] = cyc[0], "<="
        how = "its first rung, already at or below aurora's error: Cycles needs at most this"
    else:
        c, out["relation"] = None, "="
    if c is None:
        e = interpolate(cyc, a["error"], stat)
        out["cycles"] = {"how": e["how"], "samples": e["samples"], "between": e["between"], "wall_s": e["wall_s"],
                         "cpu_s": e["cpu_s"]}
    else:
        out["cycles"] = {"how": how, "samples": c["samples"], "error": c["error"], "wall_s": c[f"{stat}_wall_s"],
                         "cpu_s": c[f"{stat}_cpu_s"]}
    # A lower bound on Cycles' time is an upper bound on aurora / Cycles.
    key = {"=": "", ">=": "_at_most", "<=": "_at_least"}[out["relation"]]
    out["ratios"] = {f"aurora_over_cycles_wall{key}": out["aurora"]["wall_s"] / out["cycles"]["wall_s"],
                     f"aurora_over_cycles_cpu{key}": out["aurora"]["cpu_s"] / out["cycles"]["cpu_s"]}
    return out
