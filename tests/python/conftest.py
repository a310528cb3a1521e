"""Shared set-up for the Python suite (Blender add-on, Cycles, compare.py).

Blender's user folders are redirected to a throw-away directory *before*
bpy is imported (BLENDER_USER_RESOURCES is read once, at import), so the
extension-install test never touches the real ~/.config/blender.

The add-on imports Blender's own OpenVDB module, `openvdb`, as it would
inside Blender; the bpy wheel ships it in a site-packages folder of its own,
off sys.path. This process gets that folder at the end of sys.path. Child
processes (tools/cycles/cycles_render.py and the like) get, through PYTHONPATH, a
folder holding a link to that one module: PYTHONPATH comes before the
venv's site-packages, and the whole folder would put Blender's `pxr` ahead
of usd-core's. The linked module finds its OpenVDB library once bpy is
loaded, and whatever loads the add-on loads bpy first.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent.parent
_USER = tempfile.mkdtemp(prefix="aurora-blender-user-")
os.environ["BLENDER_USER_RESOURCES"] = _USER

for p in (HERE, ROOT / "tools"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))


def blender_site_packages() -> Path:
    """The bpy wheel's own site-packages (found without importing bpy)."""
    spec = importlib.util.find_spec("bpy")
    assert spec is not None and spec.submodule_search_locations, "no bpy module: run tools/setup"
    found = sorted(Path(spec.submodule_search_locations[0]).glob("*/python/lib/python3*/site-packages"))
    assert found, f"no site-packages inside {spec.submodule_search_locations[0]}"
    return found[-1]


_BLENDER_SITE = blender_site_packages()
sys.path.append(str(_BLENDER_SITE))
_OPENVDB_ONLY = Path(_USER) / "openvdb-module"
_OPENVDB_ONLY.mkdir()
for _module in _BLENDER_SITE.glob("openvdb.*"):
    (_OPENVDB_ONLY / _module.name).symlink_to(_module)
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(_OPENVDB_ONLY), os.environ.get("PYTHONPATH")]))


class _CheckedPopen(subprocess.Popen):
    """Every child a test starts (subprocess.run uses Popen too), kept so
    that a child that panics (exit 101) or dies of a signal the test did
    not send fails the test, whatever status the test expected."""

    def __init__(self, *args, **kwargs):
        self.stopped_on_purpose = False
        super().__init__(*args, **kwargs)
        _CHILDREN.append(self)

    def send_signal(self, sig):  # terminate() and kill() come through here
        self.stopped_on_purpose = True
        super().send_signal(sig)


_CHILDREN: list[_CheckedPopen] = []
subprocess.Popen = _CheckedPopen


@pytest.fixture(autouse=True)
def children_end_on_their_own():
    """Fails the test if a child it started exited with 101 (a Rust panic)
    or was killed by a signal it did not send."""
    first = len(_CHILDREN)
    yield
    bad = ended_badly(_CHILDREN[first:])
    del _CHILDREN[first:]
    if bad:
        pytest.fail("; ".join(bad), pytrace=False)


def ended_badly(children) -> list[str]:
    """What went wrong with each of `children` that panicked or died of a
    signal nobody sent it (one that is still running is not judged)."""
    bad = []
    for p in children:
        rc = p.poll()
        if rc is not None and not p.stopped_on_purpose and (rc == 101 or rc < 0):
            what = "panicked (exit 101)" if rc == 101 else f"was killed by signal {-rc}"
            bad.append(f"{p.args!r} {what}")
    return bad


def pytest_sessionfinish(session, exitstatus):
    import shutil

    shutil.rmtree(_USER, ignore_errors=True)


@pytest.fixture(scope="session")
def blender_user_dir() -> Path:
    return Path(_USER)


@pytest.fixture(scope="session")
def bpy():
    import bpy as _bpy

    return _bpy


@pytest.fixture(scope="session")
def cycles_render(bpy):
    import cycles_render as _cr

    return _cr


@pytest.fixture(scope="session")
def addon(cycles_render):
    """The add-on package loaded from ../../blender as `aurora_importer`."""
    return cycles_render.load_addon()


@pytest.fixture()
def fresh(bpy):
    """An empty Blender file."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy.context.scene


@pytest.fixture(scope="session")
def compare():
    import compare as _compare

    return _compare


def render_pair(cycles_render, compare, scene, vdb, out_dir: Path, samples: int, tag: str, **overrides):
    """Two renders that differ only in the seed: their mean and half their
    difference estimate the image and its Monte Carlo noise."""
    imgs, secs = [], []
    for seed in (0, 1):
        exr = Path(out_dir) / f"{tag}-{seed}.exr"
        info = cycles_render.render(scene, vdb, exr, samples, seed=seed, quiet=True, **overrides)
        imgs.append(compare.read_rgba(exr))
        secs.append(info["render_s"])
    return imgs[0], imgs[1], secs


def assert_matches(a, b, expected_rgb, expected_alpha, what: str, alpha_tol: float = 0.01,
                   max_noise: float | None = None, bright: float = 0.01, bias: float = 1e-4):
    """Monte Carlo acceptance test of two independent renders a, b (H, W, 4)
    against exact images. With M = (a + b) / 2 and D = a - b (independent
    seeds, so D carries only noise and E[D^2 / 4] = Var M):

    `bias` is the systematic error allowed per pixel, as a fraction of the
    peak (default 1e-4: float32 and quadrature slop). Cycles' biased mode
    has a small known bias where the optical depth changes within a voxel
    (its one-tap stochastic interpolation makes the optical depth of a ray
    noisy, and E[exp(-tau)] > exp(-E[tau]); measured 1e-3 of T at step
    rate 0.1 on a box edge, a few 1e-4 at 0.02): dense cases pass a
    larger, stated `bias`.

    1. total flux: |sum(M - E)| <= 5 sd + bias sum|E|, sd = sqrt(sum(D^2)) / 2
       (a 5 sigma test that the image has no overall bias);
    2. per-pixel fit: sum((M - E)^2) <= 1.5 sum(D^2 / 4) + (bias E_peak)^2 N.
       Without bias the two sides agree to within a few sqrt(2 / N) (N
       pixels with noise, hundreds here); any error comparable to the noise
       in many pixels (a half-pixel shift, a wrong ramp) inflates the left side;
    3. mean relative error over pixels brighter than 1% of the peak is at
       most 1.5 x the mean relative noise |D| / 2 (equal in expectation
       without bias) + 0.1% (float and quadrature slop);
    4. alpha within alpha_tol of the expected coverage 1 - T;
    5. the noise itself below `max_noise` (mean relative), so 1-3 are sharp.
    Returns the figures, for the report."""
    E = np.asarray(expected_rgb, np.float64)
    M = 0.5 * (a[..., :3] + b[..., :3])
    D = a[..., :3] - b[..., :3]
    peak = E.max()
    n = E.size
    sd = np.sqrt((D ** 2).sum()) / 2
    flux_err = (M - E).sum()
    assert abs(flux_err) <= 5 * sd + bias * np.abs(E).sum(), f"{what}: flux off by {flux_err:.4g} (5 sd = {5 * sd:.4g})"
    chi = ((M - E) ** 2).sum()
    noise2 = (D ** 2 / 4).sum()
    assert chi <= 1.5 * noise2 + (bias * peak) ** 2 * n, f"{what}: per-pixel misfit {chi:.4g} vs noise {noise2:.4g}"
    Es = E.sum(-1)
    sel = Es > bright * Es.max()
    rel = (np.abs(M - E).sum(-1)[sel] / Es[sel]).mean()
    noise = ((np.abs(D).sum(-1) / 2)[sel] / Es[sel]).mean()
    assert rel <= 1.5 * noise + 1e-3 + bias, f"{what}: mean relative error {rel:.4%} vs noise {noise:.4%}"
    alpha = 0.5 * (a[..., 3] + b[..., 3])
    da = np.abs(alpha - expected_alpha).max()
    assert da <= alpha_tol, f"{what}: alpha off by {da:.4f}"
    if max_noise is not None:
        assert noise <= max_noise, f"{what}: noise {noise:.4%} above the budget {max_noise:.4%}"
    return {"mean_rel_err": rel, "noise": noise, "alpha_err": da, "chi_ratio": chi / max(noise2, 1e-300)}
