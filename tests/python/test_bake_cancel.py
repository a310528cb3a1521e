"""`aurora bake --cancel-file PATH`: the cancel that needs no signal (the
Blender add-on's, on Windows too).

A bake of a scene into a folder holding a previous bake is started with
`--progress json`; once it reports its first beams done (an event read from
its stderr, never a timed wait) the test creates the cancel file. The run
must then end as Ctrl-C ends one: exit status 130, a last JSON line
`{"error": "cancelled: ...", "status": 130}`, the previous bake's files
byte for byte as they were, and (on Linux) no lock file left. The same
runs under Wine with the Windows build, where the lock file is left for the
next run into the folder to take (src/cli/cancel.rs), and the next Linux run
takes it.
"""

from __future__ import annotations

import hashlib
import json
import subprocess
from pathlib import Path

from scenes import aurora_bin, write_small_scene
from wine import WINE, windows_folder, wine_env

#: The cancelled bake's beams: enough that it is still tracing when the
#: cancel file appears (the small scene's 400 trace in well under a second;
#: 60,000 take half a minute on two cores, and a cancel is seen in 50 ms).
BEAMS = "beams.count=60000"
CANCELLED = 130


def digest(folder: Path) -> dict:
    """The bake's files (not its hidden bookkeeping) and their SHA-256."""
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.iterdir() if not p.name.startswith(".")}


def bake_and_cancel(cmd: list[str], cancel: Path, host_lines: bool = False, **popen) -> tuple[int, list[dict]]:
    """Runs `cmd` (a bake with --progress json and --cancel-file `cancel`),
    creates `cancel` once a beams line with work done arrives, and returns
    the exit status and every JSON line. With `host_lines` the lines that
    are not JSON objects are left out (Wine's own messages on the same
    stderr); without, every line must be one."""

    def parse(raw: str) -> list[dict]:
        return [] if host_lines and not raw.startswith("{") else [json.loads(raw)]

    p = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, **popen)
    lines = []
    for raw in p.stderr:
        lines += parse(raw)
        if lines and lines[-1].get("stage") == "beams" and lines[-1].get("done", 0) > 0:
            break
    assert p.poll() is None, f"the bake ended before it could be cancelled: {lines}"
    cancel.touch()
    for raw in p.stderr:
        lines += parse(raw)
    return p.wait(timeout=120), lines


def check_cancelled(rc: int, lines: list[dict]) -> None:
    assert rc == CANCELLED, lines[-3:]
    last = lines[-1]
    assert last["status"] == CANCELLED and last["error"].startswith("cancelled:"), last
    assert not any("error" in ev for ev in lines[:-1])
    # It stopped during the beams: no later stage started.
    assert not any(ev.get("stage") in ("gather", "density") for ev in lines), lines


def test_a_cancel_file_stops_a_bake_and_keeps_the_previous_one(tmp_path):
    aurora = str(aurora_bin())
    scene = write_small_scene(tmp_path / "small.toml")
    out = tmp_path / "out"
    subprocess.run([aurora, "bake", str(scene), "--out", str(out), "-q"], check=True)
    before = digest(out)
    assert "aurora.vdb" in before
    cancel = tmp_path / "cancel"
    rc, lines = bake_and_cancel([aurora, "bake", str(scene), "--out", str(out), "--seed", "8", "--set", BEAMS, "--threads", "2",
                                 "--progress", "json", "--cancel-file", str(cancel)], cancel)
    check_cancelled(rc, lines)
    assert digest(out) == before
    assert not (out / ".aurora.lock").exists(), sorted(p.name for p in out.iterdir())


def test_a_cancel_file_already_there_stops_the_bake_before_it_writes(tmp_path):
    aurora = str(aurora_bin())
    scene = write_small_scene(tmp_path / "small.toml")
    (tmp_path / "cancel").touch()
    r = subprocess.run([aurora, "bake", str(scene), "--out", str(tmp_path / "out"), "--cancel-file", str(tmp_path / "cancel"), "-q"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == CANCELLED and "cancelled" in r.stderr, r.stderr
    assert not (tmp_path / "out" / "aurora.vdb").exists()


def test_the_windows_baker_under_wine_cancels_by_the_file_too(tmp_path):
    win = windows_folder(tmp_path)
    write_small_scene(win / "small.toml")
    aurora = str(aurora_bin())
    subprocess.run([aurora, "bake", "small.toml", "--out", "out", "-q"], cwd=win, check=True)
    before = digest(win / "out")
    rc, lines = bake_and_cancel([str(WINE), "aurora.exe", "bake", "small.toml", "--out", "out", "--seed", "8", "--set", BEAMS,
                                 "--threads", "2", "--progress", "json", "--cancel-file", "cancel"], win / "cancel", host_lines=True,
                                cwd=win, env=wine_env(tmp_path))
    check_cancelled(rc, lines)
    assert digest(win / "out") == before
    # The lock file Windows leaves is the next run's to take.
    subprocess.run([aurora, "bake", "small.toml", "--out", "out", "--seed", "8", "-q"], cwd=win, check=True, timeout=300)
    assert digest(win / "out") != before
