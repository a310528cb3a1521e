"""Real schedulers bake an animation: a single-node Slurm cluster runs an
`sbatch --array=0-3` job (4 tasks, `--shard auto`) over 8 frames, and the
Open Job Description CLI runs the repository's template over 3 frames; the
frames must equal a single-process bake byte for byte, and the stage must list
the whole range.

Slurm: Debian's slurmctld, slurmd, slurm-client and munge (tools/setup
installs them). The test installs nothing: it writes a munge key, a
slurm.conf and the spool folders into a temporary folder, starts munged,
slurmctld and slurmd in the foreground on free ports with a private munge
socket (so it touches no system daemon and two runs do not collide), and
stops the three by process id in a `finally` block. It needs root (slurmd
runs jobs as their user and SlurmUser is root here).

The scene is the suite's small one (scenes.py), the binary
target/release/aurora (AURORA_BIN overrides).
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from scenes import aurora_bin, write_small_scene

ROOT = Path(__file__).resolve().parents[2]
#: The `[animation]` the frames are baked with: rays running along the curtain at 20 km/s.
ANIMATION = {"ray_speed_kms": 20.0}


def tool(name: str) -> str:
    for d in ("/usr/sbin", "/usr/bin", "/sbin", "/bin"):
        p = Path(d) / name
        if p.is_file():
            return str(p)
    found = shutil.which(name)
    assert found, f"{name} not found: run tools/setup (it installs slurmctld slurmd slurm-client munge)"
    return found


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def reference(tmp: Path, scene: Path, frames: str) -> Path:
    out = tmp / "reference"
    subprocess.run([str(aurora_bin()), "bake", str(scene), "--frames", frames, "--out", str(out), "-q"], check=True)
    return out


def assert_same_frames(out: Path, ref: Path, frames: list[int]) -> None:
    for f in frames:
        name = f"aurora.{f:04d}.vdb"
        assert (out / name).read_bytes() == (ref / name).read_bytes(), f"{name} differs from the single-process bake"
    assert (out / "aurora.usda").read_text() == (ref / "aurora.usda").read_text()


def wait_until(what: str, cond, details, deadline_s: float = 120.0) -> None:
    """Polls `cond` every 0.1 s until it holds; fails after `deadline_s`
    (generous: daemons start slowly on a loaded machine) with `details()`."""
    end = time.monotonic() + deadline_s
    while not cond():
        assert time.monotonic() < end, f"timed out after {deadline_s:.0f} s waiting for {what}: {details()}"
        time.sleep(0.1)


def stop(procs: list[subprocess.Popen]) -> None:
    for p in reversed(procs):
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
    for p in reversed(procs):
        try:
            p.wait(timeout=15)
        except subprocess.TimeoutExpired:
            p.kill()
            p.wait(timeout=5)


def test_slurm_array_bakes_frames_equal_to_one_process(tmp_path: Path) -> None:
    assert os.geteuid() == 0, "the Slurm test starts slurmd, which needs root"
    munged, slurmctld, slurmd = tool("munged"), tool("slurmctld"), tool("slurmd")
    sbatch, sinfo, scontrol = tool("sbatch"), tool("sinfo"), tool("scontrol")
    scene = tmp_path / "small.toml"
    write_small_scene(scene, animation=ANIMATION)
    ref = reference(tmp_path, scene, "1-8")

    d = tmp_path / "slurm"
    for sub in ("munge", "state", "spool", "log"):
        (d / sub).mkdir(parents=True)
    key = d / "munge" / "munge.key"
    key.write_bytes(os.urandom(1024))
    key.chmod(0o400)
    (d / "munge").chmod(0o700)
    sock = d / "munge" / "munge.socket"
    host = socket.gethostname().split(".")[0]
    mem_mb = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // (1024 * 1024)
    conf = d / "slurm.conf"
    conf.write_text(
        f"""ClusterName=aurora-test
SlurmctldHost={host}(127.0.0.1)
SlurmctldPort={free_port()}
SlurmdPort={free_port()}
AuthType=auth/munge
AuthInfo=socket={sock}
CredType=cred/munge
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SlurmUser=root
SlurmdUser=root
StateSaveLocation={d / 'state'}
SlurmdSpoolDir={d / 'spool'}
SlurmctldPidFile={d / 'slurmctld.pid'}
SlurmdPidFile={d / 'slurmd.pid'}
SlurmctldLogFile={d / 'log' / 'slurmctld.log'}
SlurmdLogFile={d / 'log' / 'slurmd.log'}
ReturnToService=2
MpiDefault=none
NodeName={host} NodeAddr=127.0.0.1 CPUs={os.cpu_count()} RealMemory={max(mem_mb - 512, 256)} State=UNKNOWN
PartitionName=test Nodes={host} Default=YES MaxTime=INFINITE State=UP
"""
    )
    env = dict(os.environ, SLURM_CONF=str(conf))
    procs: list[subprocess.Popen] = []
    try:
        procs.append(
            subprocess.Popen(
                [munged, "-F", "--force", f"--socket={sock}", f"--key-file={key}",
                 f"--pid-file={d / 'munge' / 'munged.pid'}", f"--log-file={d / 'log' / 'munged.log'}",
                 f"--seed-file={d / 'munge' / 'munged.seed'}"],
            )
        )

        def alive() -> bool:
            for p in procs:
                assert p.poll() is None, f"{p.args[0]} exited: " + "".join(
                    f.read_text(errors="replace")[-2000:] for f in (d / "log").glob("*.log")
                )
            return True

        def run(*argv: str) -> str:
            return subprocess.run(list(argv), env=env, capture_output=True, text=True).stdout.strip()

        wait_until("munged's socket", lambda: alive() and sock.exists(),
                   lambda: (d / "log" / "munged.log").read_text(errors="replace"))
        procs.append(subprocess.Popen([slurmctld, "-D", "-i", "-f", str(conf)], env=env))
        # slurmd registers with the controller: start it once that answers.
        wait_until("slurmctld to answer", lambda: alive() and run(scontrol, "ping").endswith("is UP"),
                   lambda: run(scontrol, "ping"))
        procs.append(subprocess.Popen([slurmd, "-D", "-f", str(conf)], env=env))
        wait_until("the node to be idle", lambda: alive() and run(sinfo, "-h", "-o", "%t").startswith("idle"),
                   lambda: f"node state {run(sinfo, '-h', '-o', '%t')!r}")

        out = tmp_path / "shots"
        r = subprocess.run(
            [sbatch, "--wait", "--array=0-3", "--cpus-per-task=1", f"--chdir={tmp_path}",
             f"--output={tmp_path / 'task-%a.log'}",
             str(ROOT / "farm" / "slurm" / "aurora-array.sh"), str(scene), "1-8", str(out)],
            env=dict(env, AURORA=str(aurora_bin())), capture_output=True, text=True, timeout=600,
        )
        logs = "".join(p.read_text(errors="replace") for p in sorted(tmp_path.glob("task-*.log")))
        assert r.returncode == 0, f"sbatch: {r.stdout}{r.stderr}\n{logs}"
        assert_same_frames(out, ref, list(range(1, 9)))
        # Each task baked its own share: task k frames k+1 and k+5.
        reports = sorted(p.name for p in out.glob("aurora.*.json"))
        assert reports == [f"aurora.{f:04d}.json" for f in range(1, 9)]
    finally:
        stop(procs)


def test_openjd_template_checks_and_runs(tmp_path: Path) -> None:
    # The venv's own openjd (tools/check runs .venv/bin/python without
    # activating the venv), else one on PATH.
    beside = Path(sys.executable).parent / "openjd"
    openjd = str(beside) if beside.exists() else (shutil.which("openjd") or str(beside))
    assert Path(openjd).exists(), "openjd-cli missing: run tools/setup (PIP_PKGS has openjd-cli)"
    template = ROOT / "farm" / "openjd" / "aurora-frames.yaml"
    subprocess.run([openjd, "check", str(template)], check=True)
    scene = tmp_path / "small.toml"
    write_small_scene(scene, animation=ANIMATION)
    ref = reference(tmp_path, scene, "1-3")
    out = tmp_path / "shots"
    r = subprocess.run(
        [openjd, "run", str(template), "-p", f"Scene={scene}", "-p", "Frames=1-3", "-p", f"OutDir={out}",
         "-p", f"AuroraBin={aurora_bin()}", "-p", "Threads=1"],
        capture_output=True, text=True, timeout=600,
    )
    assert r.returncode == 0, r.stdout + r.stderr
    assert_same_frames(out, ref, [1, 2, 3])
