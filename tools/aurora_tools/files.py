"""Atomic file writes: readers never see a half-written file."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path


def replace_atomic(path, write, suffix: str = ".tmp") -> None:
    """Let `write(tmp)` fill a temporary file beside `path` (named with
    `suffix`), give it the usual file mode and rename it to `path`: readers
    never see a half-written file, and on any error the temporary goes."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_atomic(path, data: bytes) -> None:
    """Write `data` to `path` through a temporary file ([`replace_atomic`])."""
    replace_atomic(path, lambda tmp: Path(tmp).write_bytes(data))
