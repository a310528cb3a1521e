"""The Windows baker under Debian's Wine, for the tests that run it.

`aurora.exe` (x86_64-pc-windows-gnu, which tools/check builds) is copied
into a folder of the test's own with a stand-in `bcryptprimitives.dll`:
Wine 8 has none, and Rust's standard library calls its `ProcessPrng` at
start on Windows 10 and later. The stand-in is three lines of C built with
mingw (RtlGenRandom). Nothing of it is shipped.
"""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
EXE = ROOT / "target" / "x86_64-pc-windows-gnu" / "release" / "aurora.exe"
WINE = Path("/usr/lib/wine/wine64")

PRNG_C = r"""
#include <windows.h>
BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);
__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T len) {
    while (len > 0) {
        ULONG n = len > 0x40000000 ? 0x40000000 : (ULONG)len;
        if (!SystemFunction036(data, n)) return FALSE;
        data += n; len -= n;
    }
    return TRUE;
}
"""


def windows_folder(tmp_path: Path) -> Path:
    """tmp_path/win holding aurora.exe and the stand-in DLL."""
    assert EXE.is_file(), f"{EXE}: cargo build --release --target x86_64-pc-windows-gnu (tools/check builds it)"
    assert WINE.is_file(), "wine64 is missing (tools/setup installs it)"
    win = tmp_path / "win"
    win.mkdir()
    shutil.copy(EXE, win / "aurora.exe")
    (tmp_path / "prng.c").write_text(PRNG_C)
    subprocess.run(["x86_64-w64-mingw32-gcc", "-shared", "-O2", "-o", str(win / "bcryptprimitives.dll"), str(tmp_path / "prng.c"),
                    "-ladvapi32"], check=True)
    return win


def wine_env(tmp_path: Path) -> dict:
    """The environment of a Wine run: a prefix of the test's own, quiet."""
    return dict(os.environ, WINEPREFIX=str(tmp_path / "prefix"), WINEDEBUG="-all")
