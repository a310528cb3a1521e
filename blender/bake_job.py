"""One run of `aurora bake` from Blender: find the binary, run it, read its
progress, cancel it, and put the result in place. No bpy here, so tests
and other hosts drive it alone.

Progress: `aurora bake --progress json` prints on stderr only JSON objects,
one per line (docs/guide.md, "Progress as JSON"): `{"stage", "done",
"total", "seconds"}` as work advances, `{"error", "status"}` when the bake
fails. A reader thread turns the lines into events; `poll` hands out the new
ones without blocking, so a modal operator can call it from a timer.

Output folder, all or nothing: the bake goes to a staging folder beside
`output_dir` (same file system) and only a bake that exits 0 replaces
`output_dir`, by two renames (old out of the way, staging in) and the removal
of the old. A failed or cancelled bake removes its staging folder and leaves
`output_dir` as it was, byte for byte; a cancelled sequence bake therefore
never leaves frames of two scenes in one folder. An existing `output_dir` is
only ever replaced if it holds nothing but a bake's own files (`_BAKE_FILES`),
so pointing the add-on at a folder of other work is an error, not a loss.
"""

from __future__ import annotations

import json
import os
import platform
import queue
import re
import shutil
import subprocess
import threading
import time
from dataclasses import dataclass
from pathlib import Path

#: Names a bake folder holds (`aurora bake`: aurora.vdb, aurora.usda,
#: bake.json; with --frames aurora.NNNN.vdb / .json; its hidden `.aurora*`
#: bookkeeping and locks; the add-on's scene.toml).
_BAKE_FILES = re.compile(r"^(aurora(\.\d+)?\.(vdb|json|usda)|bake\.json|scene\.toml|\.aurora[\w.-]*)$")
#: The scene file written into the bake folder (kept with its output).
SCENE_FILE = "scene.toml"
#: The file whose creation stops the bake (`aurora bake --cancel-file`), in
#: the staging folder: a cancel that needs no signal, so it works on Windows.
CANCEL_FILE = ".aurora-cancel"
#: Seconds a cancelled bake may take to end before it is terminated.
CANCEL_WAIT_S = 30


class BakeError(RuntimeError):
    """The bake could not run or failed; the message says why."""


#: Where an extension zip built by tools/build_extension keeps the baker:
#: bin/<Blender platform>/aurora beside this file.
BUNDLED_DIR = Path(__file__).resolve().parent / "bin"


def blender_platform() -> str | None:
    """This machine as the extension manifest's `platforms` names it
    (linux-x64, ...), or None for one we do not ship a baker for."""
    machine = {"x86_64": "x64", "amd64": "x64", "arm64": "arm64", "aarch64": "arm64"}.get(platform.machine().lower())
    system = {"linux": "linux", "darwin": "macos", "windows": "windows"}.get(platform.system().lower())
    return f"{system}-{machine}" if machine and system else None


def bundled_binary(bundled_dir: Path = BUNDLED_DIR) -> str | None:
    """The baker the extension zip brought for this platform, made
    executable if the installer's unzip dropped its mode bits (Python's
    zipfile does), or None."""
    plat = blender_platform()
    if plat is None:
        return None
    exe = bundled_dir / plat / ("aurora.exe" if plat.startswith("windows") else "aurora")
    if not exe.is_file():
        return None
    if not os.access(exe, os.X_OK):
        try:
            exe.chmod(exe.stat().st_mode | 0o111)
        except OSError:
            return None
    return str(exe) if os.access(exe, os.X_OK) else None


def find_binary(preference: str | None = None, bundled_dir: Path = BUNDLED_DIR) -> str:
    """The `aurora` executable: the add-on preference if set (the user's
    explicit choice), else the one the extension zip brought, else
    `$AURORA_BIN`, else `aurora` on PATH."""
    if preference:
        return _executable(preference, "the add-on preferences")
    bundled = bundled_binary(bundled_dir)
    if bundled:
        return bundled
    if os.environ.get("AURORA_BIN"):
        return _executable(os.environ["AURORA_BIN"], "$AURORA_BIN")
    found = shutil.which("aurora")
    if found:
        return found
    raise BakeError("no aurora binary: install the extension zip that brings it (tools/build_extension), set its path "
                    "in the add-on preferences (Edit > Preferences > Add-ons > Aurora), or $AURORA_BIN, or put `aurora` on PATH")


def _executable(cand: str, where: str) -> str:
    p = Path(cand).expanduser()
    if p.is_file() and os.access(p, os.X_OK):
        return str(p)
    raise BakeError(f"the aurora binary set in {where} ({cand}) is not an executable file")


@dataclass
class Event:
    """One line of `--progress json`."""

    stage: str = ""
    done: int = 0
    total: int = 0
    seconds: float = 0.0
    error: str | None = None
    warning: str | None = None

    @property
    def fraction(self) -> float:
        return min(1.0, self.done / self.total) if self.total > 0 else 0.0


def parse_line(line: str) -> Event:
    """An event from one stderr line; a line that is not a JSON object is an
    error event carrying the text (the binary promised JSON only)."""
    try:
        obj = json.loads(line)
    except ValueError:
        return Event(error=line.strip())
    if not isinstance(obj, dict):
        return Event(error=line.strip())
    if "warning" in obj:
        return Event(warning=str(obj["warning"]), seconds=float(obj.get("seconds", 0.0)))
    if "error" in obj:
        return Event(error=str(obj["error"]), seconds=float(obj.get("seconds", 0.0)))
    return Event(str(obj.get("stage", "")), int(obj.get("done", 0)), int(obj.get("total", 0)), float(obj.get("seconds", 0.0)))


def is_bake_folder(path: Path) -> bool:
    return path.is_dir() and all(p.is_file() and _BAKE_FILES.match(p.name) for p in path.iterdir())


class BakeJob:
    """`aurora bake SCENE --out STAGING --progress json [--frames a-b]`."""

    def __init__(self, binary: str, scene_toml: str, output_dir, frames: tuple[int, int] | None = None,
                 threads: int | None = None, sources: dict[int, str] | None = None):
        self.binary = binary
        # curtain index -> the Blender object its path came from, to name in errors.
        self.sources = sources or {}
        self.scene_toml = scene_toml
        self.output_dir = Path(output_dir).resolve()
        self.frames = frames
        self.threads = threads
        self.staging = self.output_dir.parent / f".{self.output_dir.name}.staging-{os.getpid()}-{id(self):x}"
        self.events: list[Event] = []
        self.errors: list[str] = []
        self._queue: queue.Queue = queue.Queue()
        self._proc: subprocess.Popen | None = None
        self._reader: threading.Thread | None = None

    def command(self) -> list[str]:
        cmd = [self.binary, "bake", str(self.staging / SCENE_FILE), "--out", str(self.staging), "--progress", "json",
               "--cancel-file", str(self.staging / CANCEL_FILE)]
        if self.frames is not None:
            cmd += ["--frames", f"{self.frames[0]}-{self.frames[1]}"]
        if self.threads:
            cmd += ["--threads", str(self.threads)]
        return cmd

    def start(self) -> None:
        if self.output_dir.exists() and not is_bake_folder(self.output_dir):
            raise BakeError(f"{self.output_dir} holds files that are not a bake's: choose an empty or new output folder "
                            "(a completed bake replaces the whole folder)")
        self.output_dir.parent.mkdir(parents=True, exist_ok=True)
        self.staging.mkdir()
        (self.staging / SCENE_FILE).write_text(self.scene_toml)
        self._proc = subprocess.Popen(self.command(), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.PIPE, text=True, bufsize=1)
        self._reader = threading.Thread(target=self._read, args=(self._proc.stderr,), daemon=True)
        self._reader.start()

    def _read(self, stream) -> None:
        for line in stream:
            if line.strip():
                self._queue.put(parse_line(line))
        self._queue.put(None)  # end of stream

    def poll(self) -> list[Event]:
        """New events since the last call (never blocks)."""
        new = []
        while True:
            try:
                ev = self._queue.get_nowait()
            except queue.Empty:
                break
            if ev is None:
                continue
            new.append(ev)
            if ev.error is not None:
                self.errors.append(ev.error)
        self.events += new
        return new

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    @property
    def returncode(self) -> int | None:
        """The baker's exit status once it ended (130: cancelled), else None."""
        return None if self._proc is None else self._proc.poll()

    def wait(self, on_event=None) -> int:
        """Run to the end (synchronous use), passing each event to `on_event`."""
        assert self._proc is not None, "start() first"
        while True:
            alive = self._proc.poll() is None
            for ev in self.poll():
                if on_event:
                    on_event(ev)
            if not alive:
                break
            time.sleep(0.05)
        self._reader.join()
        for ev in self.poll():
            if on_event:
                on_event(ev)
        return self._proc.returncode

    def cancel(self) -> None:
        """Stop the bake and remove its staging folder; `output_dir` is untouched.

        The stop is asked for by creating the bake's cancel file (no signal:
        Windows has none to send); the baker sees it within 50 ms and exits
        as after Ctrl-C. One that has not ended after `CANCEL_WAIT_S` is
        terminated."""
        if self._proc is not None and self._proc.poll() is None:
            try:
                (self.staging / CANCEL_FILE).touch()
                self._proc.wait(timeout=CANCEL_WAIT_S)
            except (OSError, subprocess.TimeoutExpired):
                self._proc.terminate()
                try:
                    self._proc.wait(timeout=CANCEL_WAIT_S)
                except subprocess.TimeoutExpired:
                    self._proc.kill()
                    self._proc.wait()
        if self._reader is not None:
            self._reader.join(timeout=30)
        shutil.rmtree(self.staging, ignore_errors=True)

    def finish(self) -> Path:
        """After the process ended: move a successful bake into place, or
        clean up and raise BakeError with the binary's messages."""
        rc = self.wait()
        if rc != 0:
            shutil.rmtree(self.staging, ignore_errors=True)
            raise BakeError(self.explain("; ".join(self.errors) or f"aurora bake exited with status {rc}"))
        old = self.output_dir.parent / f".{self.output_dir.name}.old-{os.getpid()}-{id(self):x}"
        if self.output_dir.exists():
            self.output_dir.rename(old)
        self.staging.rename(self.output_dir)
        shutil.rmtree(old, ignore_errors=True)
        return self.output_dir

    def explain(self, msg: str) -> str:
        """The binary's message in the artist's terms: the scene file it
        names is the panel's (the staging folder is gone, and the output
        folder's scene.toml is the previous bake's), and each curtain[i] it
        names whose path is a curve is followed by that curve's name."""
        msg = msg.replace(str(self.staging / SCENE_FILE), "the Aurora panel's scene")
        msg = msg.replace(str(self.staging), str(self.output_dir))
        named = sorted({int(i) for i in re.findall(r"curtain\[(\d+)\]", msg)} & self.sources.keys())
        if named:
            msg += " (" + "; ".join(f"curtain[{i}] is the curve {self.sources[i]!r}" for i in named) + ")"
        return msg

    def run(self, on_event=None) -> Path:
        """start + wait + finish: the synchronous bake (background mode)."""
        self.start()
        try:
            self.wait(on_event)
        except BaseException:
            self.cancel()
            raise
        return self.finish()

    def result_file(self) -> Path:
        """The file to import: aurora.vdb, or the first frame of a sequence."""
        if self.frames is None:
            return self.output_dir / "aurora.vdb"
        return self.output_dir / f"aurora.{self.frames[0]:04d}.vdb"
