"""Samples per pixel needed for a given error, by pixel-sampling scheme.

    .venv/bin/python benchmarks/render/pixel_sampling.py --vdb BAKE/aurora.vdb \
        --bin NEW=target/release/aurora [--bin OLD=path/to/older/aurora] \
        [--size 160x90] [--out target/pixel-sampling]

The default scene, volume only (terrain none), at --size; the reference is
`aurora render` of the first binary at 8x8 sub-pixels x 8 spp x 2 seeds,
box-downsampled (as benchmarks/side_by_side/side_by_side.py). Each binary
renders a ladder of spp with SEEDS seeds; the error is
tools/cycles/compare.py's mean relative error, averaged over the seeds; the
spp to reach each target is interpolated log-log between the rungs that
bracket it. Prints a table and writes
pixel_sampling.json in --out. Compare binaries built from commits that
differ only in how pixel positions are drawn.
"""
import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
# The shared package aurora_tools, and the side-by-side benchmark's runners and metrics.
sys.path[:0] = [str(ROOT / "tools"), str(ROOT / "benchmarks" / "side_by_side")]
from aurora_tools import image_compare as compare  # noqa: E402
from aurora_tools.toml_io import edit_toml  # noqa: E402
from metrics import downsample, interpolate  # noqa: E402
from runners import timed_run  # noqa: E402

LADDER = [4, 8, 16, 32, 64, 128]
SEEDS = (11, 12, 13)
TARGETS = (0.02, 0.01, 0.005)


def render(binary, scene, vdb, out, spp, seed):
    _, wall, cpu = timed_run([binary, "render", scene, "--vdb", vdb, "--out", out, "--spp", spp, "--seed", seed,
                              "--threads", 2, "-q"], "aurora render")
    return wall, cpu


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--vdb", required=True)
    p.add_argument("--bin", action="append", required=True, help="NAME=PATH of an aurora binary")
    p.add_argument("--size", default="160x90")
    p.add_argument("--out", default=str(ROOT / "target" / "pixel-sampling"))
    a = p.parse_args(argv)
    w, h = (int(x) for x in a.size.split("x"))
    bins = dict(b.split("=", 1) for b in a.bin)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    first = next(iter(bins.values()))
    text = subprocess.run([first, "scene", "default"], capture_output=True, text=True, check=True).stdout
    base = {("terrain", "kind"): "none", ("render", "spp"): 16}
    scene = out / "scene.toml"
    scene.write_text(edit_toml(text, {**base, ("render", "width"): w, ("render", "height"): h}))
    f = 8
    ref_scene = out / "reference.toml"
    ref_scene.write_text(edit_toml(text, {**base, ("render", "width"): w * f, ("render", "height"): h * f}))
    refs = []
    for s in (9101, 9102):
        path = out / f"reference-{s}.exr"
        if not path.exists():
            render(first, ref_scene, a.vdb, path, 8, s)
        refs.append(downsample(compare.read_rgba(path), f))
    ref = 0.5 * (refs[0] + refs[1])
    own = compare.metrics(refs[0], refs[1])["mean_rel_err"] / 2
    res = {"size": [w, h], "vdb": str(a.vdb), "reference_own_error": own, "seeds": list(SEEDS), "schemes": {}}
    for name, binary in bins.items():
        ladder = []
        for n in LADDER:
            errs, walls = [], []
            for s in SEEDS:
                path = out / f"{name}-{n:04d}-{s}.exr"
                wall, _ = render(binary, scene, a.vdb, path, n, s)
                errs.append(compare.metrics(compare.read_rgba(path), ref)["mean_rel_err"])
                walls.append(wall)
            e = sum(errs) / len(errs)
            ladder.append({"samples": n, "error": e, "errors": errs, "best_wall_s": min(walls),
                           "best_cpu_s": min(walls)})
            print(f"{name:>10} {n:5d} spp: error {100 * e:.3f} %  ({min(walls):.2f} s)", file=sys.stderr, flush=True)
        res["schemes"][name] = {"binary": str(binary), "ladder": ladder,
                                "to_reach": {str(t): interpolate(ladder, t) for t in TARGETS}}
    (out / "pixel_sampling.json").write_text(json.dumps(res, indent=1))
    print(f"reference own error {100 * own:.3f} %; spp needed (mean relative error, {w}x{h}, volume only):")
    print(f"{'scheme':>10} " + " ".join(f"{100 * t:>8.1f}%" for t in TARGETS))
    for name, r in res["schemes"].items():
        cells = []
        for t in TARGETS:
            x = r["to_reach"][str(t)]
            cells.append(f"{x['samples']:>8.1f}{'' if x['how'] == 'interpolated' else '*'}")
        print(f"{name:>10} " + " ".join(cells))
    print("(* extrapolated)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
