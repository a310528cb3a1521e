"""The Windows build bakes under Wine, and its bake is Linux's byte for byte.

`aurora.exe` (x86_64-pc-windows-gnu, which tools/check builds) bakes the
default scene under Debian's Wine, and so does the Linux binary; both must
be the pinned bake (benchmarks/pins/current.txt), which a farm mixing the
platforms gets from either. Wine 8 has no `bcryptprimitives.dll`, whose `ProcessPrng` Rust's
standard library calls at start on Windows 10 and later; wine.py builds a
stand-in from three lines of C with mingw (RtlGenRandom) beside the copied
exe. Nothing of it is shipped.

The transcendental functions (exp, ln, powf, sin, atan2, ..., and powi,
which LLVM lowers to the C library's pow on Windows) go through one
implementation on every platform, src/util/fmath.rs (the `libm` crate),
never through the platform's C math library (glibc here, the MinGW runtime
there), whose functions round differently: so the VDB and the stage are the
same bytes. Before that, the grids differed by one or two steps of the
stored half float.
"""

from __future__ import annotations

import hashlib
import subprocess

from scenes import aurora_bin
from wine import ROOT, WINE, windows_folder, wine_env


def pinned(name: str) -> str:
    """The SHA-256 benchmarks/pins/current.txt holds for the default bake's `name`."""
    for line in (ROOT / "benchmarks" / "pins" / "current.txt").read_text().splitlines():
        digest, _, pin = line.partition("  ")
        if pin == f"bake/{name}":
            return digest
    raise AssertionError(f"no pin for bake/{name}")


def test_the_windows_default_bake_under_wine_is_linux_s_byte_for_byte(tmp_path):
    win = windows_folder(tmp_path)
    env = wine_env(tmp_path)
    w = subprocess.run([str(WINE), "aurora.exe", "bake", "default", "--out", "wout", "--threads", "2", "-q"], cwd=win, env=env,
                       capture_output=True, text=True, timeout=900)
    assert w.returncode == 0, w.stdout + w.stderr
    subprocess.run([str(aurora_bin()), "bake", "default", "--out", "lout", "--threads", "2", "-q"], cwd=win, check=True)
    for name in ("aurora.vdb", "aurora.usda"):
        lin, wnd = (win / "lout" / name).read_bytes(), (win / "wout" / name).read_bytes()
        assert len(lin) > 0 and lin == wnd, f"{name}: Windows's {len(wnd)} bytes differ from Linux's {len(lin)}"
        assert hashlib.sha256(lin).hexdigest() == pinned(name), f"{name}: not the pinned default bake"
