"""`tools/build_extension --all`: one extension zip per platform, each with
its own baker, read back with tools that are not ours.

Each zip is named as Blender's `extension build --split-platforms` names a
platform's build (`<id>-<version>-<platform, - as _>.zip`: Blender 5.0.1's
bl_pkg/cli/blender_ext.py), names that one platform in its manifest's
`platforms`, and holds blender/'s files (the same in every zip) and one
baker, bin/<platform>/aurora (aurora.exe on Windows). The bakers' headers
are read with LLVM's llvm-readobj and llvm-objdump (Debian's LLVM 14,
tools/setup): ELF x86-64; PE32+ x86-64 for the Windows console, importing
only Windows' own DLLs; Mach-O arm64 (and x86-64) executables linking only
macOS's libraries (/usr/lib, /System/Library), the arm64 one with a code
signature, which macOS needs before it runs an arm64 binary at all. The
signature is checked as the kernel checks an ad-hoc one (Apple's
cs_blobs.h): its CodeDirectory is SHA-256, flagged ad hoc, covers the file
up to the signature, and every page's hash is that page's; a copy with one
byte of code changed fails the same check.
"""

from __future__ import annotations

import hashlib
import re
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "tools" / "build_extension"
#: The platforms --all ships, and the baker's name on each.
PLATFORMS = {"linux-x64": "aurora", "windows-x64": "aurora.exe", "macos-arm64": "aurora"}
PREFIX = "aurora_importer-0.1.0"
#: Where macOS's own libraries live.
MACOS_SYSTEM = ("/usr/lib/", "/System/Library/")
#: The DLLs every Windows has (the system's, and the C runtime Windows ships).
WINDOWS_DLLS = {"kernel32.dll", "ntdll.dll", "msvcrt.dll", "userenv.dll", "ws2_32.dll", "bcryptprimitives.dll", "advapi32.dll",
                "api-ms-win-core-synch-l1-2-0.dll"}


@pytest.fixture(scope="module")
def zips(tmp_path_factory) -> dict[str, zipfile.ZipFile]:
    out = tmp_path_factory.mktemp("dist")
    r = subprocess.run([sys.executable, str(BUILD), "--all", "--out", str(out)], capture_output=True, text=True, timeout=3600)
    assert r.returncode == 0, r.stderr
    paths = [Path(line) for line in r.stdout.split()]
    assert sorted(p.name for p in paths) == sorted(f"{PREFIX}-{p.replace('-', '_')}.zip" for p in PLATFORMS)
    return {p: zipfile.ZipFile(out / f"{PREFIX}-{p.replace('-', '_')}.zip") for p in PLATFORMS}


@pytest.fixture(scope="module")
def bakers(zips, tmp_path_factory) -> dict[str, Path]:
    """Each zip's baker, extracted."""
    d = tmp_path_factory.mktemp("bakers")
    out = {}
    for plat, z in zips.items():
        out[plat] = d / plat
        out[plat].write_bytes(z.read(f"bin/{plat}/{PLATFORMS[plat]}"))
    return out


def readobj(*args) -> str:
    return subprocess.run(["llvm-readobj", *args], capture_output=True, text=True, check=True).stdout


def objdump(*args) -> str:
    return subprocess.run(["llvm-objdump", *args], capture_output=True, text=True, check=True).stdout


def test_each_zip_names_its_one_platform_and_ships_its_baker(zips, tmp_path):
    plain = subprocess.run([sys.executable, str(BUILD), "--no-binary", "--out", str(tmp_path)], capture_output=True, text=True,
                           check=True)
    add_on = zipfile.ZipFile(plain.stdout.strip())
    common = {n: add_on.read(n) for n in add_on.namelist() if n != "blender_manifest.toml"}
    for plat, z in zips.items():
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        assert manifest["platforms"] == [plat]
        assert manifest["id"] == "aurora_importer" and manifest["version"] == "0.1.0"
        baker = f"bin/{plat}/{PLATFORMS[plat]}"
        assert [n for n in z.namelist() if n.startswith("bin/")] == [baker]
        assert (z.getinfo(baker).external_attr >> 16) & 0o777 == 0o755
        assert {n: z.read(n) for n in z.namelist() if n not in (baker, "blender_manifest.toml")} == common


def test_the_linux_baker_is_an_elf_x86_64_executable(bakers):
    h = readobj("--file-headers", str(bakers["linux-x64"]))
    assert "Format: elf64-x86-64" in h and "Machine: EM_X86_64 (0x3E)" in h
    assert re.search(r"Type: (Executable|SharedObject) ", h)  # a PIE is ET_DYN
    assert bakers["linux-x64"].read_bytes() == (ROOT / "target" / "release" / "aurora").read_bytes()


def test_the_windows_baker_is_a_pe32_plus_x86_64_console_program_of_system_dlls(bakers):
    h = readobj("--file-headers", str(bakers["windows-x64"]))
    assert "Format: COFF-x86-64" in h and "Machine: IMAGE_FILE_MACHINE_AMD64 (0x8664)" in h
    assert "Magic: 0x20B" in h  # PE32+
    assert "Subsystem: IMAGE_SUBSYSTEM_WINDOWS_CUI (0x3)" in h
    dlls = {m.lower() for m in re.findall(r"Name: (\S+\.dll)", readobj("--coff-imports", str(bakers["windows-x64"])), re.I)}
    assert dlls and dlls <= WINDOWS_DLLS, dlls - WINDOWS_DLLS  # no mingw runtime DLL to ship beside it


def macho_headers(path: Path) -> tuple[str, list[str], list[str]]:
    """llvm-objdump's Mach-O header line, load command names, and dylibs."""
    text = objdump("--macho", "--private-headers", str(path))
    header = text.split("Load command")[0]
    commands = re.findall(r"^\s*cmd (LC_\w+)", text, re.M)
    dylibs = re.findall(r"cmd LC_(?:LOAD|LOAD_WEAK|REEXPORT|LOAD_UPWARD)_DYLIB\n\s*cmdsize \d+\n\s*name (\S+) \(offset", text)
    return header, commands, dylibs


@pytest.mark.parametrize("plat,cpu", [("macos-arm64", "ARM64")])
def test_the_macos_bakers_are_mach_o_executables_linking_only_the_system(bakers, plat, cpu):
    header, commands, dylibs = macho_headers(bakers[plat])
    assert re.search(rf"MH_MAGIC_64\s+{cpu}\s+\S+\s+\S+\s+EXECUTE", header), header
    assert "LC_MAIN" in commands and "LC_BUILD_VERSION" in commands
    # macOS 11, as Rust's target has it (Blender 4.2 itself needs 11.2), not zig's default of a recent one.
    text = objdump("--macho", "--private-headers", str(bakers[plat]))
    assert re.search(r"cmd LC_BUILD_VERSION\n.*\n\s*platform macos\n.*\n\s*minos 11\.0\n", text), "not for macOS 11"
    assert "/usr/lib/libSystem.B.dylib" in dylibs
    assert all(d.startswith(MACOS_SYSTEM) for d in dylibs), dylibs
    if plat == "macos-arm64":
        assert commands.count("LC_CODE_SIGNATURE") == 1


def be32(b: bytes, at: int) -> int:
    return int.from_bytes(b[at : at + 4], "big")


def check_adhoc_signature(data: bytes) -> str:
    """Checks a Mach-O file's ad-hoc code signature as Apple's cs_blobs.h
    lays it out and returns its identifier; raises AssertionError if a page
    is not what the signature hashed."""
    ncmds, at, sig = int.from_bytes(data[16:20], "little"), 32, None
    for _ in range(ncmds):
        cmd, size = int.from_bytes(data[at : at + 4], "little"), int.from_bytes(data[at + 4 : at + 8], "little")
        if cmd == 0x1D:  # LC_CODE_SIGNATURE: linkedit_data_command
            sig = (int.from_bytes(data[at + 8 : at + 12], "little"), int.from_bytes(data[at + 12 : at + 16], "little"))
        at += size
    assert sig is not None, "no LC_CODE_SIGNATURE"
    off, size = sig
    blob = data[off : off + size]
    assert be32(blob, 0) == 0xFADE0CC0, "not an embedded signature SuperBlob"
    slots = {be32(blob, 12 + 8 * i): be32(blob, 16 + 8 * i) for i in range(be32(blob, 8))}
    cd = blob[slots[0] :]  # CSSLOT_CODEDIRECTORY
    assert be32(cd, 0) == 0xFADE0C02, "no CodeDirectory"
    flags, hash_off, ident_off, n_code, code_limit = be32(cd, 12), be32(cd, 16), be32(cd, 20), be32(cd, 28), be32(cd, 32)
    hash_size, hash_type, page = cd[36], cd[37], 1 << cd[39]
    assert flags & 0x2, "not ad hoc (CS_ADHOC)"
    assert (hash_type, hash_size) == (2, 32), "not SHA-256"
    assert code_limit == off, "the signature does not cover the file up to itself"
    assert n_code == -(-code_limit // page)
    for i in range(n_code):
        page_bytes = data[i * page : min((i + 1) * page, code_limit)]
        want = cd[hash_off + i * hash_size : hash_off + (i + 1) * hash_size]
        assert hashlib.sha256(page_bytes).digest() == want, f"page {i} is not what the signature hashed"
    return cd[ident_off:].split(b"\0", 1)[0].decode()


def test_the_macos_arm64_baker_carries_a_valid_ad_hoc_signature(bakers):
    data = bakers["macos-arm64"].read_bytes()
    assert check_adhoc_signature(data).startswith("aurora")
    # One byte of code changed: the same check refuses it, as macOS would.
    text_at = 0x4000 + 0x100
    tampered = data[:text_at] + bytes([data[text_at] ^ 0xFF]) + data[text_at + 1 :]
    with pytest.raises(AssertionError, match="is not what the signature hashed"):
        check_adhoc_signature(tampered)


def load(name: str, path: Path):
    import importlib.util

    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


#: (platform.system(), platform.machine()) as Python reports them on each.
SYSTEMS = {"linux-x64": ("Linux", "x86_64"), "windows-x64": ("Windows", "AMD64"), "macos-arm64": ("Darwin", "arm64")}


def test_the_add_on_finds_its_platforms_baker_in_each_zip(zips, tmp_path, monkeypatch):
    """The add-on's bake_job (no bpy) on each platform, as Python names it
    there: its platform is the one Blender's own extension code names
    (bl_pkg/cli/blender_ext.py's platform_from_this_system, bpy 5.0.1), and
    in the installed zip it finds bin/<platform>/aurora[.exe], made
    executable; the zip of another platform gives it none."""
    import importlib.util
    import platform

    bake_job = load("aurora_bake_job", ROOT / "blender" / "bake_job.py")
    spec = importlib.util.find_spec("bpy")
    cli = next(Path(spec.submodule_search_locations[0]).glob("*/scripts/addons_core/bl_pkg/cli/blender_ext.py"))
    blender_ext = load("blender_ext", cli)
    for plat, (system, machine) in SYSTEMS.items():
        monkeypatch.setattr(platform, "system", lambda s=system: s)
        monkeypatch.setattr(platform, "machine", lambda m=machine: m)
        assert bake_job.blender_platform() == blender_ext.platform_from_this_system() == plat
        for other, z in zips.items():
            installed = tmp_path / plat / other
            z.extractall(installed)  # zipfile drops the mode bits, as Blender's installer may
            found = bake_job.bundled_binary(installed / "bin")
            if other == plat:
                assert found == str(installed / "bin" / plat / PLATFORMS[plat])
                assert found.endswith(".exe") == (plat == "windows-x64")
            else:
                assert found is None, (plat, other, found)
