"""Running what the studies time: commands (with their wall and CPU
time), the aurora binary (bake, render), the Cycles worker (one long-lived
bpy process rendering through the add-on), and the facts a run records
about the machine and the tree."""

from __future__ import annotations

import json
import os
import platform
import re
import resource
import shutil
import subprocess
import sys
import time
import traceback
from pathlib import Path

from aurora_tools import ROOT
from aurora_tools.blender_worker import BlenderWorker, answers
from settings import THREADS


class Failure(Exception):
    """A tool is missing, a command failed or a check did not hold."""


def log(msg: str) -> None:
    print(f"[side_by_side {time.strftime('%H:%M:%S')}] {msg}", file=sys.stderr, flush=True)


# ---------------------------------------------------------------- commands

def run(cmd, what: str, **kw) -> subprocess.CompletedProcess:
    cmd = [str(c) for c in cmd]
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, **kw)
    except FileNotFoundError as e:
        raise Failure(f"{what}: cannot run {cmd[0]}: {e}") from e
    if r.returncode != 0:
        raise Failure(f"{what} failed (exit {r.returncode}): {' '.join(cmd)}\n{r.stdout[-2000:]}\n{r.stderr[-4000:]}")
    return r


def timed_run(cmd, what: str) -> tuple[subprocess.CompletedProcess, float, float]:
    """Run a command; return it, its wall time and its CPU time (user + sys)."""
    c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    r = run(cmd, what)
    wall = time.perf_counter() - t0
    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r, wall, (c1.ru_utime - c0.ru_utime) + (c1.ru_stime - c0.ru_stime)


def machine_facts() -> dict:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    mem_kb = None
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal:"):
                mem_kb = int(line.split()[1])
    except OSError:
        pass
    nproc = run(["nproc"], "nproc").stdout.strip()
    return {
        "nproc": int(nproc),
        "cpu_model": cpu,
        "mem_total_kb": mem_kb,
        "kernel": platform.release(),
        "python": platform.python_version(),
        "hostname": platform.node(),
    }


def git_facts() -> dict:
    head = run(["git", "-C", ROOT, "rev-parse", "HEAD"], "git rev-parse").stdout.strip()
    dirty = run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"], "git status").stdout.strip()
    return {"commit": head, "dirty": bool(dirty)}


def load() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


# ---------------------------------------------------------------- aurora

class Tools:
    def __init__(self):
        self.aurora = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
        if not (self.aurora.is_file() and os.access(self.aurora, os.X_OK)):
            raise Failure(f"{self.aurora}: the aurora binary is missing (cargo build --release --locked)")
        self.vdb_bench = ROOT / "target" / "release" / "examples" / "vdb_write_bench"
        self.cpp_bench = ROOT / "target" / "openvdb_write_bench"  # built by vdb_write_bench from the .cpp
        if not shutil.which("/usr/bin/time"):
            raise Failure("/usr/bin/time is missing (apt-get install time): needed for seed2014's peak memory")

    def build_vdb_bench(self) -> None:
        log("cargo build --release --locked --example vdb_write_bench")
        run(["cargo", "build", "--release", "--locked", "--example", "vdb_write_bench", "-q"], "cargo build", cwd=ROOT)
        if not self.vdb_bench.is_file():
            raise Failure(f"{self.vdb_bench}: not built")

    def version(self) -> str:
        return run([self.aurora, "--version"], "aurora --version").stdout.strip()


def import_pyopenvdb():
    try:
        import pyopenvdb
    except ImportError as e:
        raise Failure(f"cannot import pyopenvdb (Debian's python3-openvdb; run with .venv/bin/python): {e}") from e
    return pyopenvdb


def bake(tools: Tools, scene, out_dir: Path) -> dict:
    if out_dir.exists():
        shutil.rmtree(out_dir)
    _, wall, cpu = timed_run([tools.aurora, "bake", scene, "--out", out_dir, "-q", "--threads", THREADS],
                             f"aurora bake {scene}")
    j = json.loads((out_dir / "bake.json").read_text())
    return {"wall_s": wall, "cpu_s": cpu, "bake": j}


def aurora_render(tools: Tools, scene: Path, vdb: Path, out: Path, spp: int, shadow: int, seed: int | None = None,
                  adaptive: bool = False):
    cmd = [tools.aurora, "render", scene, "--vdb", vdb, "--out", out, "--spp", spp, "--shadow-samples", shadow,
           "--threads", THREADS]
    if adaptive:
        cmd.append("--adaptive")
    if seed is not None:
        cmd += ["--seed", seed]
    r, wall, cpu = timed_run(cmd, "aurora render")
    m = re.search(r"(\d+) primary rays in ([0-9.]+) s .*?(\d+) shadow samples", r.stderr)
    if not m:
        raise Failure(f"aurora render printed no timing line:\n{r.stderr[-2000:]}")
    return {"wall_s": wall, "cpu_s": cpu, "pixel_loop_s": float(m.group(2)), "primary_rays": int(m.group(1)),
            "shadow_samples": int(m.group(3))}


# ---------------------------------------------------------------- Cycles

class CyclesWorker(BlenderWorker):
    """One long-lived bpy process (side_by_side.py --cycles-worker): requests
    as JSON lines on its stdin, answers as JSON lines on a pipe of their own
    (Blender prints to stdout; that goes to a log file)."""

    def __init__(self, log_path: Path):
        super().__init__([Path(__file__).with_name("side_by_side.py"), "--cycles-worker"], log_path,
                         what="Cycles worker", failure=Failure, tmp_prefix="side-by-side-blender-")


def worker_main(fd: int) -> int:
    """The bpy side of CyclesWorker."""
    say = answers(fd)

    try:
        import bpy
        import numpy as np

        from aurora_tools import cycles as cycles_render
        from aurora_tools import image_compare as compare
        from aurora_tools.addon import load_addon

        addon = load_addon()
        from aurora_importer.vdb_pad import pad_vdb
    except Exception as e:  # noqa: BLE001 - reported to the parent, which fails
        say({"error": f"cannot import bpy / the add-on (run with .venv/bin/python, bpy 5.0.1): {e!r}"})
        return 1
    say({"blender": bpy.app.version_string, "addon": addon.__name__})
    for line in sys.stdin:
        req = json.loads(line)
        try:
            op = req.pop("op")
            if op == "pad":
                r = pad_vdb(req["src"], req["dst"])
                say({"seconds": r.seconds, "grids": r.grids})
            elif op == "render":
                info = cycles_render.render(req["scene"], req["vdb"], req["out"], samples=req["samples"],
                                            quiet=True, pad=False, threads=req["threads"],
                                            step_rate=req["step_rate"], seed=req.get("seed", 0),
                                            adaptive_threshold=req.get("adaptive"))
                say({k: v for k, v in info.items() if isinstance(v, (int, float, str))})
            elif op == "terrain_mask":
                m = compare.terrain_mask(req["scene"], req["width"], req["height"])
                np.save(req["out"], m)
                say({"pixels": int(m.sum())})
            else:
                say({"error": f"unknown op {op}"})
        except Exception as e:  # noqa: BLE001
            say({"error": f"{op}: {e!r}\n{traceback.format_exc()}"})
    return 0
