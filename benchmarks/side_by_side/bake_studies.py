"""The bake-side studies: 1. the VDB writers (ours, OpenVDB's C++ writer,
pyopenvdb) on one bake's grids, their files read back equal; 2. the gather
methods' times; 4. the seed2014 bake's wall time, memory and stages."""

from __future__ import annotations

import itertools
import json
import os
import re
import shutil
import tempfile
import time
from pathlib import Path

from metrics import best
from runners import Failure, Tools, bake, import_pyopenvdb, load, log, run
from scenes import gather_scenes
from settings import THREADS


# ---------------------------------------------------------------- 1. VDB writer

def grids_equal(vdb, a_path: Path, b_path: Path) -> dict:
    """Read both files with pyopenvdb; every grid must match by name, type,
    transform, active voxel count and every active voxel (coordinates and
    value, exactly). Returns what was compared; raises Failure otherwise."""
    ga, _ = vdb.readAll(str(a_path))
    gb, _ = vdb.readAll(str(b_path))
    by_name = {g.name: g for g in gb}
    if sorted(g.name for g in ga) != sorted(by_name):
        raise Failure(f"{a_path} has grids {sorted(g.name for g in ga)}, {b_path} has {sorted(by_name)}")
    out = {"grids": {}}
    end = object()
    for g in ga:
        h = by_name[g.name]
        if g.valueTypeName != h.valueTypeName:
            raise Failure(f"{g.name}: {a_path} stores {g.valueTypeName}, {b_path} {h.valueTypeName}")
        for p in ((0, 0, 0), (1, 2, 3)):
            if g.transform.indexToWorld(p) != h.transform.indexToWorld(p):
                raise Failure(f"{g.name}: transforms differ between {a_path} and {b_path}")
        if g.activeVoxelCount() != h.activeVoxelCount():
            raise Failure(f"{g.name}: {g.activeVoxelCount()} active voxels in {a_path}, {h.activeVoxelCount()} in {b_path}")
        n = 0
        # Both trees iterate in coordinate order, so equal sets of active
        # voxels with equal values give equal sequences.
        for x, y in itertools.zip_longest(g.citerOnValues(), h.citerOnValues(), fillvalue=end):
            if x != y:
                raise Failure(f"{g.name}: active values differ between {a_path} and {b_path}: {x} against {y}")
            n += 1
        out["grids"][g.name] = {"type": g.valueTypeName, "active_voxels": n, "leaves": g.leafCount()}
    out["equal"] = True
    return out


def file_facts(vdb, path: Path) -> dict:
    meta = vdb.readAllGridMetadata(str(path))
    return {
        "bytes": path.stat().st_size,
        "grids": {m.name: {"class": m.gridClass, "file_compression": m.metadata.get("file_compression"),
                           "half": bool(m.metadata.get("is_saved_as_half_float", False))} for m in meta},
    }


def study_vdb(tools: Tools, cfg: dict, bake_dir: Path, out: Path) -> dict:
    vdb = import_pyopenvdb()
    src = bake_dir / "aurora.vdb"
    bake = json.loads((bake_dir / "bake.json").read_text())
    comp = bake["files"]["compression"]
    if comp != "blosc-active-mask" or bake["files"]["half_emission"]:
        raise Failure(f"the writer study's bake is {comp}, half {bake['files']['half_emission']}: expected blosc-active-mask, f32")
    d = out / "vdb"
    d.mkdir(parents=True, exist_ok=True)
    tools.build_vdb_bench()

    # pyopenvdb: the grids fully in memory (delayed loading is off), class
    # set to unknown like the C++ tool (no effect on Blosc; kept for parity).
    t0 = time.perf_counter()
    grids, file_meta = vdb.readAll(str(src))
    read_s = time.perf_counter() - t0
    for g in grids:
        g.gridClass = vdb.GridClass.UNKNOWN
    voxels = sum(g.activeVoxelCount() for g in grids)
    leaves = sum(g.leafCount() for g in grids)
    py_path = d / "pyopenvdb_blosc+active-mask.vdb"
    cpp_blosc_path = d / "openvdb_blosc+active-mask.vdb"

    runs = {"aurora_zip": [], "cpp_zip": [], "aurora_blosc": [], "pyopenvdb_blosc": [], "cpp_blosc": []}
    sizes = {}

    def ours_and_cpp(mode, ours, cpp):
        r = run([tools.vdb_bench, "--input", src, "--modes", mode, "--repeat", 1, "--threads", THREADS,
                 "--out-dir", d], "examples/vdb_write_bench")
        rows = [ln for ln in r.stdout.splitlines() if ln.startswith(f"csv,{mode},")]
        if len(rows) != 1:
            raise Failure(f"vdb_write_bench printed no csv row:\n{r.stdout}")
        f = rows[0].split(",")
        runs[ours].append(float(f[4]))
        sizes[ours] = int(f[8])
        if cpp is not None:
            runs[cpp].append(float(f[6]))
            sizes[cpp] = int(f[9])

    def ours_and_cpp_zip():
        ours_and_cpp("zip+active-mask", "aurora_zip", "cpp_zip")

    def ours_blosc():
        # The example also writes OpenVDB's Blosc file (openvdb_blosc+active-mask.vdb):
        # cpp_blosc below rewrites it and is the C++ Blosc time reported.
        ours_and_cpp("blosc+active-mask", "aurora_blosc", None)

    def cpp_blosc():
        if not tools.cpp_bench.is_file():
            raise Failure(f"{tools.cpp_bench} missing: examples/vdb_write_bench builds it with g++ (tools/setup)")
        r = run([tools.cpp_bench, src, cpp_blosc_path, "blosc+active-mask", "--repeat", 1], "openvdb_write_bench")
        v = json.loads(r.stdout.strip().splitlines()[-1])
        runs["cpp_blosc"].append(float(v["best"]))
        sizes["cpp_blosc"] = int(v["bytes"])

    def py_blosc():
        fd, tmp = tempfile.mkstemp(prefix=f".{py_path.name}.", suffix=".tmp.vdb", dir=d)
        os.close(fd)
        try:
            t = time.perf_counter()
            vdb.write(tmp, grids=grids, metadata=file_meta)
            runs["pyopenvdb_blosc"].append(time.perf_counter() - t)
            os.replace(tmp, py_path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
        sizes["pyopenvdb_blosc"] = py_path.stat().st_size

    writers = [ours_and_cpp_zip, ours_blosc, py_blosc, cpp_blosc]
    for rep in range(cfg["vdb_repeats"]):
        log(f"vdb: run {rep + 1}/{cfg['vdb_repeats']}")
        k = rep % len(writers)  # rotate who goes first
        for w in writers[k:] + writers[:k]:
            w()

    ours_file = d / "aurora_zip+active-mask.vdb"
    ours_blosc_file = d / "aurora_blosc+active-mask.vdb"
    cpp_file = d / "openvdb_zip+active-mask.vdb"
    log("vdb: reading the files back with pyopenvdb")
    t0 = time.perf_counter()
    eq_py = grids_equal(vdb, src, py_path)
    eq_cpp = grids_equal(vdb, src, cpp_file)
    eq_ours = grids_equal(vdb, src, ours_file)
    eq_cpp_blosc = grids_equal(vdb, src, cpp_blosc_path)
    eq_ours_blosc = grids_equal(vdb, src, ours_blosc_file)
    check_s = time.perf_counter() - t0
    files = {
        "aurora_zip": file_facts(vdb, ours_file),
        "cpp_zip": file_facts(vdb, cpp_file),
        "aurora_blosc": file_facts(vdb, ours_blosc_file),
        "pyopenvdb_blosc": file_facts(vdb, py_path),
        "cpp_blosc": file_facts(vdb, cpp_blosc_path),
    }
    for k, f in files.items():
        if f["bytes"] != sizes[k]:
            raise Failure(f"{k}: the timed write reported {sizes[k]} bytes, the file has {f['bytes']}")
    b = {k: best(v) for k, v in runs.items()}
    lib = ".".join(map(str, vdb.LIBRARY_VERSION))
    return {
        "input": {"file": str(src), "bytes": src.stat().st_size, "grids": [g.name for g in grids],
                  "active_voxels": voxels, "leaves": leaves, "value_types": [g.valueTypeName for g in grids],
                  "bake_vdb_write_s": bake["files"]["vdb_write_seconds"], "pyopenvdb_read_s": read_s},
        "repeats": cfg["vdb_repeats"],
        "writers": {
            "aurora_zip": {"what": f"aurora vdb::write (Rust, {THREADS} threads), encode + write the file, "
                                   "ZIP + active mask, f32, class as baked (fog volume); timed by "
                                   "examples/vdb_write_bench.rs"},
            "cpp_zip": {"what": f"OpenVDB {lib} C++ io::File::write (benchmarks/vdb_write/openvdb_write_bench.cpp), "
                                "ZIP + active mask, f32, grid class set to unknown (OpenVDB drops ZIP for fog "
                                "volumes); timed by the same example, alternating with ours"},
            "aurora_blosc": {"what": f"aurora vdb::write (Rust, {THREADS} threads), BLOSC + active mask (the "
                                     "default writer; tree bytes identical to OpenVDB's), f32, fog volume; "
                                     "timed by examples/vdb_write_bench.rs"},
            "pyopenvdb_blosc": {"what": f"pyopenvdb {lib} write(path, grids, metadata) from Python; pyopenvdb has "
                                        "no compression setting: io::File's default, BLOSC + active mask, f32, "
                                        "class set to unknown (no effect on Blosc)"},
            "cpp_blosc": {"what": f"OpenVDB {lib} C++ io::File::write, BLOSC + active mask (pyopenvdb's flags), "
                                  "f32, class as read (fog volume: OpenVDB keeps Blosc for fog volumes): the same "
                                  "work as pyopenvdb without Python"},
        },
        "seconds": runs,
        "best_s": b,
        "bytes": sizes,
        "files": files,
        "ratios": {
            "ours_over_cpp_zip_time": b["aurora_zip"] / b["cpp_zip"],
            "ours_over_cpp_zip_bytes": sizes["aurora_zip"] / sizes["cpp_zip"],
            "ours_zip_over_pyopenvdb_blosc_time": b["aurora_zip"] / b["pyopenvdb_blosc"],
            "ours_zip_over_pyopenvdb_blosc_bytes": sizes["aurora_zip"] / sizes["pyopenvdb_blosc"],
            "pyopenvdb_over_cpp_blosc_time": b["pyopenvdb_blosc"] / b["cpp_blosc"],
            "ours_blosc_over_ours_zip_time": b["aurora_blosc"] / b["aurora_zip"],
            "ours_blosc_over_cpp_blosc_time": b["aurora_blosc"] / b["cpp_blosc"],
            "ours_blosc_over_cpp_blosc_bytes": sizes["aurora_blosc"] / sizes["cpp_blosc"],
        },
        "read_back": {"ours_vs_pyopenvdb": eq_py, "ours_vs_cpp_zip": eq_cpp, "bake_vs_bench_ours": eq_ours,
                      "ours_vs_cpp_blosc": eq_cpp_blosc, "ours_blosc": eq_ours_blosc, "check_s": check_s,
                      "how": "pyopenvdb readAll of both files; per grid: name, value type, transform, active "
                             "voxel count, then every active voxel's coordinates and value compared exactly"},
    }


# ---------------------------------------------------------------- 2. gather

def study_gather(tools: Tools, cfg: dict, scene_text: str, main_bake: dict, out: Path) -> dict:
    methods = ["kdtree", "splat", "report2014"]
    d = out / "gather"
    scenes = gather_scenes(scene_text, d, methods)
    rows = {m: [] for m in methods}
    first = main_bake["bake"]["stats"]["gather"]  # the scene's own gather (splat by default)
    if first in rows:
        rows[first].append(main_bake)  # the main bake is that method's first run
    for rep in range(cfg["gather_repeats"]):
        for m in methods:
            if m == first and rep == 0:
                continue
            log(f"gather: {m} run {rep + 1}/{cfg['gather_repeats']}")
            rows[m].append(bake(tools, scenes[m], d / f"bake-{m}"))
    res = {"methods": {}, "repeats": cfg["gather_repeats"]}
    for m in methods:
        st = [r["bake"]["stats"] for r in rows[m]]
        if any(s["gather"] != m for s in st):
            raise Failure(f"bake.json says gather {[s['gather'] for s in st]}, expected {m}")
        g = [s["times_s"]["gather"] for s in st]
        res["methods"][m] = {
            "gather_s": g, "best_gather_s": best(g),
            "total_s": [s["times_s"]["total"] for s in st], "bake_wall_s": [r["wall_s"] for r in rows[m]],
            "photons": st[0]["photons"], "active_voxels": st[0]["active_voxels"], "leaves": st[0]["leaves"],
        }
    k = res["methods"]["kdtree"]["best_gather_s"]
    res["ratios"] = {
        "splat_over_kdtree_time": res["methods"]["splat"]["best_gather_s"] / k,
        "report2014_over_kdtree_time": res["methods"]["report2014"]["best_gather_s"] / k,
    }
    res["note"] = ("report2014 computes the report's kernel-weighted average colour of the photons binned in a "
                   "uniform grid (the leaves), not a density: same stage, different estimator, not the same image")
    return res


# ---------------------------------------------------------------- 4. seed2014

def study_seed2014(tools: Tools, out: Path) -> dict:
    d = out / "seed2014"
    if d.exists():
        shutil.rmtree(d)
    la = load()
    log("seed2014: aurora bake seed2014 (about 5 minutes on 2 cores)")
    r = run(["/usr/bin/time", "-v", tools.aurora, "bake", "seed2014", "--out", d, "-q", "--threads", THREADS],
            "aurora bake seed2014")
    txt = r.stderr
    wall = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (?:(\d+):)?(\d+):([0-9.]+)", txt)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", txt)
    user = re.search(r"User time \(seconds\): ([0-9.]+)", txt)
    sys_ = re.search(r"System time \(seconds\): ([0-9.]+)", txt)
    if not (wall and rss and user and sys_):
        raise Failure(f"cannot read /usr/bin/time -v output:\n{txt[-2000:]}")
    wall_s = int(wall.group(1) or 0) * 3600 + int(wall.group(2)) * 60 + float(wall.group(3))
    j = json.loads((d / "bake.json").read_text())
    times = j["stats"]["times_s"]
    stages = {k: v for k, v in times.items() if k != "total"}
    top = max(stages, key=stages.get)
    return {
        "wall_s": wall_s, "peak_rss_kb": int(rss.group(1)),
        "cpu_s": float(user.group(1)) + float(sys_.group(1)),
        "stages_s": stages, "stages_total_s": times["total"],
        "vdb_write_s": j["files"]["vdb_write_seconds"], "vdb_bytes": j["files"]["vdb_bytes"],
        "dominant_stage": top, "dominant_share_of_wall": stages[top] / wall_s,
        "beams": j["stats"]["beams"], "photons": j["stats"]["photons"],
        "active_voxels": j["stats"]["active_voxels"], "leaves": j["stats"]["leaves"],
        "voxel_size_km": j["stats"]["voxel_size_km"], "gather": j["stats"]["gather"],
        "threads": j.get("threads"), "load_before": la, "load_after": load(),
    }
