"""benchmarks/side_by_side/side_by_side.py --quick: the whole benchmark runs and its output holds together.

The quick mode bakes a reduced default scene (1,000 beams, 1 km voxels),
times the VDB writers once, bakes the three gather methods, renders 64x36
ladders with `aurora render` and Cycles, and skips seed2014; `--cases
volume,terrain,dome` adds the dome master (the oval preset reduced to 1,000
beams and 2 km voxels, baked and rendered at 64x64). Asserted here:
the JSON's structure; every ratio finite and positive; the files of the
three OpenVDB writers read back (pyopenvdb) with our file's active voxels and
values; errors fall with samples for both renderers; Cycles' flux agrees with
the reference; the dome's errors are taken inside the fisheye's image circle
and its figure against aurora's lowest rung is a measured time or a bound,
never an extrapolation. The speed numbers themselves are the full run's business
(benchmarks/side_by_side/), never a timed test's.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
TOOL = ROOT / "benchmarks" / "side_by_side" / "side_by_side.py"


def test_quick_side_by_side_runs_and_is_consistent(tmp_path):
    out = tmp_path / "sbs"
    env = dict(os.environ)
    env.setdefault("AURORA_BIN", str(ROOT / "target" / "release" / "aurora"))
    r = subprocess.run([sys.executable, TOOL, "--quick", "--cases", "volume,terrain,dome", "--out", out],
                       capture_output=True, text=True, env=env, timeout=900)
    assert r.returncode == 0, f"side_by_side --quick failed ({r.returncode}):\n{r.stdout[-3000:]}\n{r.stderr[-5000:]}"
    res = json.loads((out / "side_by_side.json").read_text())
    text = (out / "side_by_side.txt").read_text()
    assert text == r.stdout, "the table on stdout and side_by_side.txt differ"
    assert sorted(p.name for p in out.iterdir() if p.name.startswith(".")) == [], "temporary files left behind"

    assert res["mode"] == "quick"
    m = res["machine"]
    assert m["nproc"] >= 1 and m["cpu_model"] and m["mem_total_kb"] > 0
    assert len(res["load_start"]) == 3 and len(res["load_end"]) == 3
    assert len(res["git"]["commit"]) == 40
    assert res["seed2014"] == {"skipped": True, "why": "--quick"}

    # Every ratio finite and positive, and every study contributes.
    ratios = res["ratios"]
    for key in ("vdb_write.ours_over_cpp_zip_time", "vdb_write.ours_over_cpp_zip_bytes",
                "vdb_write.ours_zip_over_pyopenvdb_blosc_time", "vdb_write.pyopenvdb_over_cpp_blosc_time",
                "vdb_write.ours_blosc_over_ours_zip_time", "vdb_write.ours_blosc_over_cpp_blosc_bytes",
                "gather.splat_over_kdtree_time", "gather.report2014_over_kdtree_time",
                "render.volume.aurora_over_cycles_wall", "render.volume.aurora_over_cycles_cpu",
                "render.terrain.aurora_over_cycles_wall", "render.terrain.aurora_over_cycles_cpu"):
        assert key in ratios, key
    for k, v in ratios.items():
        assert math.isfinite(v) and v > 0, (k, v)
        assert k in text, f"{k} missing from the table"

    # VDB writers: the files read back equal, and each file holds what it says.
    v = res["vdb_write"]
    for pair in ("ours_vs_pyopenvdb", "ours_vs_cpp_zip", "ours_vs_cpp_blosc", "bake_vs_bench_ours", "ours_blosc"):
        rb = v["read_back"][pair]
        assert rb["equal"] is True, pair
        assert sum(g["active_voxels"] for g in rb["grids"].values()) == v["input"]["active_voxels"], pair
    assert v["input"]["active_voxels"] > 0
    comp = {k: {g["file_compression"] for g in f["grids"].values()} for k, f in v["files"].items()}
    assert comp["aurora_zip"] == comp["cpp_zip"] == {"zip + active values"}, comp
    assert comp["pyopenvdb_blosc"] == comp["cpp_blosc"] == comp["aurora_blosc"] == {"blosc + active values"}, comp
    for k, f in v["files"].items():
        assert f["bytes"] == v["bytes"][k] > 0, k
        assert len(v["seconds"][k]) == v["repeats"] == 1, k

    # Gather: three methods, same photons.
    g = res["gather"]["methods"]
    assert sorted(g) == ["kdtree", "report2014", "splat"]
    assert len({x["photons"] for x in g.values()}) == 1

    # Render ladders: errors fall with samples for both renderers; Cycles'
    # flux agrees with the reference; equal-error samples lie on the ladder.
    for case in ("volume", "terrain"):
        c = res["render"]["cases"][case]
        assert c["reference"]["own_error_estimate"] < c["target_error"], case
        for who in ("aurora", "cycles"):
            lad = c["ladders"][who]
            assert len(lad) >= 3, (case, who)
            errs = [e["error"] for e in lad]
            assert all(a > b for a, b in zip(errs, errs[1:])), (case, who, errs)
            assert all(e["best_wall_s"] > 0 and e["best_cpu_s"] > 0 for e in lad), (case, who)
            eq = c["equal_error"][who]
            if eq["how"] == "interpolated":
                assert lad[0]["samples"] <= eq["samples"] <= lad[-1]["samples"], (case, who, eq)
            else:
                # The quick ladder's first rung already beats the target (the
                # default bake is smooth since expected deposition, and pixel
                # samples are antithetic): the equal-error point lies below it.
                assert lad[0]["error"] <= c["target_error"] and 0 < eq["samples"] <= lad[0]["samples"], (case, who, eq, lad[0])
        assert c["cycles_converged"]["agrees"], (case, c["cycles_converged"])

    # The dome master: its own bake, errors inside the image circle, the
    # figure at aurora's lowest rung.
    dome = res["render"]["cases"]["dome"]
    assert dome["size"] == [64, 64] and dome["bake"]["preset"] == "oval"
    assert dome["bake"]["active_voxels"] > 0
    assert "image circle" in dome["what"]["metric"]
    for who in ("aurora", "cycles"):
        lad = dome["ladders"][who]
        assert len(lad) >= 3, who
        errs = [e["error"] for e in lad]
        assert all(a > b for a, b in zip(errs, errs[1:])), (who, errs)
        assert all(e["max_alpha_diff"] < 0.5 for e in lad), (who, [e["max_alpha_diff"] for e in lad])
    low = dome["at_aurora_lowest_rung"]
    assert low["relation"] in ("=", ">=", "<="), low
    assert low["cycles"]["how"] != "extrapolated: the ladder does not reach the target", low
    assert set(dome["ratios"]) == set(low["ratios"]) and dome["ratios"], dome["ratios"]
    assert dome["cycles_converged"]["agrees"], dome["cycles_converged"]
    assert "dome: the oval preset's dome master at 64x64" in text
