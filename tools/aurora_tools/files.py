"""Atomic file writes: readers never see a half-written file."""

from __future__ import annotations

import os
import sys
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


def write_altitude_table(path, comments: list[str], header: str, rows) -> None:
    """A table by altitude as the crate's data files hold it: `# ` comment
    lines (source, version, terms), the header, then a row per altitude
    (km to 0.1, the values to 6 significant digits), written atomically."""
    lines = [f"# {c}\n" for c in comments] + [header + "\n"]
    lines += [f"{r[0]:.1f}," + ",".join(f"{x:.6g}" for x in r[1:]) + "\n" for r in rows]
    write_atomic(path, "".join(lines).encode())
    print(f"wrote {path}: {len(rows)} rows", file=sys.stderr)
