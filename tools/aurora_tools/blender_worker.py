"""A long-lived bpy process: bpy takes seconds to import and Blender prints
to stdout, so a tool that renders many times starts one child (a script of
its own, given the write end of a pipe) and talks to it in JSON lines:
requests on the child's stdin, answers on the pipe, Blender's own output
to a log file. The first answer is the child's greeting.

Parent: `BlenderWorker([script, "--worker-flag"], log_path)`, then
`ask(op=..., ...)` and `close()`. Child: `say = answers(fd)`, then
`say({...})` once to greet and once per request."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path


def answers(fd: int):
    """The child's side: a function writing one JSON answer line to the pipe."""
    out = os.fdopen(fd, "w")

    def say(obj) -> None:
        out.write(json.dumps(obj) + "\n")
        out.flush()

    return say


class BlenderWorker:
    """The parent's side. `argv` runs the child under this Python with the
    pipe's file descriptor appended; an answer holding "error", or the child
    dying, raises `failure` (with the log's tail)."""

    def __init__(self, argv, log_path: Path, what: str = "Blender worker", failure=RuntimeError,
                 tmp_prefix: str = "blender-worker-"):
        self.what = what
        self.failure = failure
        r, w = os.pipe()
        self.log = open(log_path, "w")
        env = dict(os.environ)
        env.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix=tmp_prefix))
        self.proc = subprocess.Popen([sys.executable, *[str(a) for a in argv], str(w)], stdin=subprocess.PIPE,
                                     stdout=self.log, stderr=subprocess.STDOUT, pass_fds=(w,), text=True, env=env)
        os.close(w)
        self.answers = os.fdopen(r, "r")
        self.log_path = log_path
        self.info = self._read()

    def _read(self) -> dict:
        line = self.answers.readline()
        if not line:
            self.proc.wait()
            tail = Path(self.log_path).read_text(errors="replace")[-3000:]
            raise self.failure(f"the {self.what} died (exit {self.proc.returncode}); its log {self.log_path}:\n{tail}")
        a = json.loads(line)
        if "error" in a:
            raise self.failure(f"{self.what}: {a['error']}")
        return a

    def ask(self, **req) -> dict:
        self.proc.stdin.write(json.dumps(req, default=str) + "\n")
        self.proc.stdin.flush()
        return self._read()

    def close(self):
        if self.proc.poll() is None:
            self.proc.stdin.close()
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        if not self.answers.closed:
            self.answers.close()
        if not self.log.closed:
            self.log.close()
