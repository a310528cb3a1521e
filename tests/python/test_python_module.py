"""The Python module `aurora` (python/, installed into .venv by tools/setup)
against the command line's own files: the same library answers both, so
the arrays must be the files' values.

- Scenes: `Scene.set` applies `--set`'s rules: the TOML equals `aurora
  scene --set`'s, and a bad value raises `aurora.InputError` with the
  command line's message (key, value, range).
- Profile: every array value, printed as the CSV prints it (`{:.6e}`,
  altitude `{:.2f}`), is the CSV's text: equal, not close.
- Render: the RGBA image and a line's narrow-band image in rayleigh
  within 1e-6 relative of `aurora render`'s EXR (both f32 from the same
  seeded trace: measured equal).
- Keogram: equal to `aurora keogram`'s EXR, with its rows' angles.
- Bake: progress reaches the callback; an interrupt (SIGINT, as Ctrl-C in a
  terminal or a notebook's stop) raises KeyboardInterrupt before the bake
  ends, and the folder's previous bake is kept byte for byte with no lock
  left behind; an exception in the callback stops it too.
"""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from scenes import aurora_bin

import aurora  # python/aurora, installed by tools/setup: missing is a failure

# An arc 80 km long and 4 km wide along x (magnetic east-west, declination
# 0), drifting north; frames 10 s apart; its 557.7 nm on a grid of its own;
# a camera on the ground 60 km south (tests/cli/keogram.rs's scene).
SCENE = """seed = 3
[[curtain]]
center = [0.0, 0.0]
length = 80.0
width = 4.0
bend_km = 0.0
energy_flux = 5.0
char_energy_kev = 3.0
soft_fraction = 0.0
[footprint]
resolution = [32, 8]
uniform = true
[beams]
count = 4000
b_inclination_deg = 90.0
b_declination_deg = 0.0
[earth]
radius_km = 0.0
[grid]
voxel_size = 1.0
density_a = 0.0
lines = ["5577"]
[photons]
radius_km = 1.0
[animation]
fps = 0.1
drift_km = 30.0
drift_period_s = 80.0
[camera]
position = [0.0, -60.0, 0.1]
look_at = [0.0, 0.0, 100.0]
[render]
width = 48
height = 27
spp = 2
[terrain]
kind = "none"
"""


def cli(*args) -> subprocess.CompletedProcess:
    return subprocess.run([str(aurora_bin()), *map(str, args)], capture_output=True, text=True)


def ok(*args) -> subprocess.CompletedProcess:
    r = cli(*args)
    assert r.returncode == 0, f"aurora {' '.join(map(str, args))}: {r.stderr[-3000:]}"
    return r


@pytest.fixture()
def scene_file(tmp_path) -> Path:
    p = tmp_path / "s.toml"
    p.write_text(SCENE)
    return p


def test_the_module_is_the_installed_build():
    assert Path(aurora.__file__).parent.name == "aurora" and hasattr(aurora, "_aurora")
    assert "default" in aurora.presets()


def test_set_follows_the_command_lines_rules(scene_file):
    s = aurora.Scene("default")
    s.set("curtain[0].energy_flux", 20)
    s.set("render.width", 64)
    s.set("camera.up", [0, 1, 0])
    r = ok("scene", "default", "--set", "curtain[0].energy_flux=20", "--set", "render.width=64", "--set", "camera.up=[0, 1, 0]")
    body = r.stdout[r.stdout.index("seed = "):]
    assert s.to_toml() == body
    # Out of range: the command line's message, naming key, value and range; the scene unchanged.
    bad = cli("scene", "default", "--set", "curtain[0].energy_flux=-5")
    assert bad.returncode == 2
    with pytest.raises(aurora.InputError) as e:
        s.set("curtain[0].energy_flux", -5)
    want = bad.stderr.split("--set curtain[0].energy_flux=-5: ", 1)[1].strip()
    assert str(e.value) == f"Scene.set curtain[0].energy_flux=-5: {want}"
    assert "curtain[0].energy_flux = -5" in str(e.value) and "(0, 10000]" in str(e.value)
    assert s.to_toml() == body
    with pytest.raises(aurora.InputError, match="did you mean `width`"):
        s.set("render.widht", 5)
    # A file, and an unknown name naming the presets.
    assert aurora.Scene(str(scene_file)).size == (48, 27)
    with pytest.raises(aurora.InputError, match="default"):
        aurora.Scene("no-such-scene")


def csv_table(path: Path) -> tuple[list[str], list[list[str]]]:
    lines = [l for l in path.read_text().splitlines() if not l.startswith("#")]
    return lines[0].split(","), [l.split(",") for l in lines[1:]]


def printed(name: str, x: float) -> float:
    """The value as the CSV prints it (Rust's `{:.6e}`, `{:.2}` for the
    altitude, the curtain's index as an integer), read back."""
    if name == "curtain":
        return float(int(x))
    return float(f"{x:.2f}") if name == "altitude_km" else float(f"{x:.6e}")


def test_profile_arrays_are_the_csvs_values(scene_file, tmp_path):
    out = tmp_path / "p.csv"
    ok("profile", scene_file, "--out", out, "--quiet")
    p = aurora.profile(aurora.Scene(str(scene_file)))
    header, rows = csv_table(out)
    assert list(p.columns) == header and len(p.columns["altitude_km"]) == len(rows) > 100
    for j, name in enumerate(header):
        got = [printed(name, x) for x in p.columns[name]]
        want = [float(r[j]) for r in rows]
        assert got == want, f"column {name} differs from the CSV"
    assert p.units["oi_5577_ver_cm3_s"] == "photons cm^-3 s^-1" and p.units["ionization"] == "ion pairs s^-1"
    cheader, crows = csv_table(tmp_path / "p.columns.csv")
    assert list(p.column_brightness) == cheader
    for j, name in enumerate(cheader):
        assert [printed(name, x) for x in p.column_brightness[name]] == [float(r[j]) for r in crows], name
    # The 557.7 nm column is 1-1.4 kR per erg cm^-2 s^-1 at a few keV (Rees & Luckey 1974).
    assert 800 < p.column_brightness["oi_5577_r_per_erg"][0] < 1600


def bake_sequence(scene_file: Path, tmp_path: Path, frames: str = "1-3") -> Path:
    seq = tmp_path / "seq"
    ok("bake", scene_file, "--frames", frames, "--out", seq, "--quiet")
    return seq


def test_render_equals_the_cli_exr(scene_file, tmp_path):
    from aurora_tools.exr_io import read_exr_layers, read_rgba

    seq = bake_sequence(scene_file, tmp_path, "2")
    vdb = aurora.frame_vdb(seq, 2)
    s = aurora.Scene(str(scene_file))
    for grid in (None, "line_5577"):
        exr = tmp_path / f"r-{grid}.exr"
        ok("render", scene_file, "--vdb", vdb, "--out", exr, "--quiet", *(["--grid", grid] if grid else []))
        got = aurora.render(s, vdb, grid=grid)
        if grid is None:
            want = read_rgba(exr)
            assert got.shape == want.shape == (27, 48, 4) and got.dtype == np.float32
        else:
            (want,) = read_exr_layers(exr).values()
            want = want[..., 0]
            assert got.shape == want.shape == (27, 48) and got.units.startswith("R (rayleigh)") and "applied" in got.air
        assert want.max() > 0
        err = np.abs(got - want).max() / np.abs(want).max()
        print(f"render grid={grid}: largest difference {err:.3e} of the peak")
        assert err <= 1e-6
    # The sequence's frame by number, as --frame does.
    assert np.array_equal(aurora.render(s, seq, grid="line_5577", frame=2), aurora.render(s, vdb, grid="line_5577"))
    with pytest.raises(aurora.InputError, match="line_6300"):
        aurora.render(s, vdb, grid="line_6300")


def test_keogram_equals_the_cli_exr(scene_file, tmp_path):
    from aurora_tools.exr_io import read_exr_layers

    seq = bake_sequence(scene_file, tmp_path)
    out = tmp_path / "k.exr"
    ok("keogram", scene_file, "--vdb", seq, "--frame", "1-3", "--grid", "line_5577", "--out", out, "--quiet")
    (want,) = read_exr_layers(out).values()
    k = aurora.keogram(aurora.Scene(str(scene_file)), seq, "1-3")
    assert k.values.shape == (361, 3) and k.values.units.startswith("R (rayleigh)")
    assert np.array_equal(k.values, want[..., 0]), "keogram differs from the EXR"
    assert list(k.frames) == [1, 2, 3] and np.allclose(k.times_s, [0, 10, 20])
    assert k.scan_deg[0] == 0 and k.scan_deg[-1] == 180 and k.elevation_deg[180] == 90
    assert k.values.max() > 1000


def digest(folder: Path) -> dict:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def test_bake_reports_progress_and_an_interrupt_keeps_the_previous_bake(scene_file, tmp_path):
    out = tmp_path / "out"
    s = aurora.Scene(str(scene_file))
    seen = []
    t0 = time.monotonic()
    summary = aurora.bake(s, out, progress=lambda stage, done, total: seen.append((stage, done, total)))
    one_bake_s = time.monotonic() - t0
    assert "aurora.vdb" in summary and any(stage == "beams" for stage, _, _ in seen)
    before = digest(out)
    assert {"aurora.vdb", "aurora.usda", "bake.json"} <= set(before)

    # Another bake into the folder, interrupted as it starts its beams: 500
    # times the beams, so run to its end it would take some 500 times the
    # first bake; stopped at its next chunk of beams, it returns within a
    # few bakes' time (the work's thread has ended when the call returns).
    s.set("seed", 4)
    s.set("beams.count", 2_000_000)
    asked = []

    def interrupt(stage, done, total):
        asked.append((stage, done, total))
        if stage == "beams" and sum(a[0] == "beams" for a in asked) == 1:
            os.kill(os.getpid(), signal.SIGINT)

    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        aurora.bake(s, out, progress=interrupt)
    stopped_s = time.monotonic() - t0
    print(f"a bake of 4000 beams {one_bake_s:.2f} s; the interrupted bake of 2e6 returned after {stopped_s:.2f} s")
    assert any(a[0] == "beams" for a in asked)
    assert stopped_s < 50 * one_bake_s + 5.0, "the interrupt did not stop the bake"
    assert digest(out) == before, "the interrupted bake touched the previous one"

    # An exception in the callback stops it the same way.
    class Stop(Exception):
        pass

    def fail(stage, done, total):
        if stage == "beams":
            raise Stop()

    with pytest.raises(Stop):
        aurora.bake(s, out, progress=fail)
    assert digest(out) == before
    # The folder is free: a bake into it goes through.
    s.set("beams.count", 4000)
    aurora.bake(s, out)
    assert digest(out)["aurora.vdb"] != before["aurora.vdb"]


def test_skymap_of_a_zenith_fisheye():
    s = aurora.Scene("default")
    for k, v in {"camera.up": [0.0, 1.0, 0.0], "camera.projection": "fisheye", "camera.fov_deg": 180.0,
                 "camera.position": [0.0, 0.0, 0.0], "camera.look_at": [0.0, 0.0, 1.0], "render.width": 33,
                 "render.height": 33}.items():
        s.set(k, v)
    with pytest.raises(aurora.InputError, match=r"\[site\]"):
        aurora.skymap(s)
    m = aurora.skymap(s, 110.0, origin=(67.0, 20.0))
    assert m["el"].shape == (33, 33) and m["alt"] == 110.0
    assert m["el"][16, 16] == pytest.approx(90.0) and m["lat"][16, 16] == pytest.approx(67.0)
    assert np.isnan(m["el"][0, 0]) and np.isnan(m["lat"][0, 0])
    # North at the top, east on the left (seen from below, as imagers show it).
    assert m["lat"][5, 16] > 67.0 and m["lon"][16, 5] > 20.0
    assert m["az"][5, 16] == pytest.approx(0.0, abs=1e-9) and m["az"][16, 5] == pytest.approx(90.0)
