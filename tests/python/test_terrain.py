"""Terrain lit by an emissive slab, Cycles through tools/cycles/cycles_render.py.

Closed form: under an infinite non-absorbing slab of thickness H
and emission e, every direction of the upper hemisphere sees radiance
e H / mu, so the irradiance is E = integral e H / mu * mu d omega = 2 pi e H
and a Lambertian ground of albedo a has radiance a E / pi = 2 a e H. The
finite slab of the test misses part of the sky; synth.slab_irradiance
integrates exactly what it covers (and the absorbing case), the oracle the
renders are held to, and the closed form must hold to 5%.

The camera looks straight down (orthographic) at the ground, from above
the slab (A, B: the camera ray crosses the slab, then meets the terrain) or
below it (C). Pixel radiance = slab emission on the way down + T * ground
radiance; alpha = 1 - T of the slab (terrain holdout, blender/material.py).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import synth
from conftest import render_pair

ALBEDO = (0.3, 0.5, 0.7)
E_SLAB = np.array([0.5, 1.0, 1.5])  # per km


@pytest.fixture(scope="module")
def near_slab(tmp_path_factory):
    """60 km wide, 1 km thick slab just above the ground: voxel 0.25 km,
    centres at z = 0.25 .. 1.0 (field from 0 to 1.25 km, mid-plane 0.625),
    x, y centres at +-29.875 (half-width to mid-ramp: 30 km)."""
    d = tmp_path_factory.mktemp("near_slab")
    h, n_xy, n_z = 0.25, 240, 4
    dens, em = synth.slab_arrays(n_xy, n_z, 1.0, E_SLAB)
    vdb = synth.write_vdb(d / "slab.vdb", h, (-29.875, -29.875, 0.25), dens, em)
    return {"dir": d, "vdb": vdb, "path": n_z * h, "z_mid": 0.625, "A": 30.0}


@pytest.fixture(scope="module")
def far_slab(tmp_path_factory):
    """200 km wide, 2 voxels (1 km) thick, centres at z = 100, 101 km."""
    d = tmp_path_factory.mktemp("far_slab")
    dens, em = synth.slab_arrays(200, 2, 1.0, E_SLAB)
    return synth.write_vdb(d / "far.vdb", 1.0, (-99.5, -99.5, 100.0), dens, em)


def down_camera(z):
    return {"position": [0.0, 0.0, z], "look_at": [0.0, 0.0, 0.0], "up": [0, 1, 0],
            "projection": "orthographic", "ortho_height": 1.0}


def check_uniform(a, b, expected_rgb, expected_alpha, what, rel_bias=0.0):
    """Every pixel sees the same thing (1 km window, 30+ km slab): hold the
    image mean to the expected value within 5 sd of the mean (sd from the
    seed difference) plus `rel_bias`, and every alpha within 0.01."""
    M = 0.5 * (a[..., :3] + b[..., :3]).reshape(-1, 3)
    D = (a[..., :3] - b[..., :3]).reshape(-1, 3)
    sd = np.sqrt((D ** 2).sum(0)) / 2 / len(M)
    mean = M.mean(0)
    err = mean - expected_rgb
    assert np.all(np.abs(err) <= 5 * sd + rel_bias * expected_rgb + 1e-6), \
        f"{what}: mean {mean} vs expected {expected_rgb} (5 sd = {5 * sd})"
    alpha = 0.5 * (a[..., 3] + b[..., 3])
    assert np.abs(alpha - expected_alpha).max() <= 0.01, f"{what}: alpha {alpha.min()}..{alpha.max()} vs {expected_alpha}"
    return {"mean": mean, "expected": expected_rgb, "rel_err": err / expected_rgb, "rel_sd": sd / expected_rgb}


def test_ground_under_wide_emissive_slab_is_2_albedo_e_h(near_slab, cycles_render, compare, tmp_path):
    s = near_slab
    scene = synth.write_scene(tmp_path / "a.toml", down_camera(5.0), 8, 8, spp=16, density_scale=0.0,
                              terrain={"kind": "plane", "height": 0.0, "albedo": list(ALBEDO)})
    a, b, secs = render_pair(cycles_render, compare, scene, s["vdb"], tmp_path, 256, "a", terrain_lighting="paths")
    E = synth.slab_irradiance(E_SLAB, 0.0, s["path"], s["z_mid"], s["A"])
    L_ground = np.array(ALBEDO) / math.pi * E
    closed = 2 * np.array(ALBEDO) * E_SLAB * s["path"]
    assert np.allclose(L_ground, closed, rtol=0.05)  # the finite slab is wide enough
    expected = E_SLAB * s["path"] + L_ground  # slab on the way down, T = 1
    fig = check_uniform(a, b, expected, 0.0, "non-absorbing slab")
    # The ground alone, against the closed form 2 a e H, within 5%.
    ground = fig["mean"] - E_SLAB * s["path"]
    assert np.allclose(ground, closed, rtol=0.05), f"ground {ground} vs 2 a e H = {closed}"
    print("slab, no absorption:", fig, "ground / (2 a e H):", ground / closed, "render s", secs)


def test_absorbing_slab_over_terrain_radiance_and_alpha(near_slab, cycles_render, compare, tmp_path):
    """The camera ray crosses the absorbing slab, then ends on the terrain:
    L = (e / sigma)(1 - T) + T L_ground, alpha = 1 - T (the terrain's holdout)."""
    s = near_slab
    sigma = 0.5
    scene = synth.write_scene(tmp_path / "b.toml", down_camera(5.0), 8, 8, spp=16, density_scale=sigma,
                              terrain={"kind": "plane", "height": 0.0, "albedo": list(ALBEDO)})
    a, b, secs = render_pair(cycles_render, compare, scene, s["vdb"], tmp_path, 256, "b", terrain_lighting="paths")
    T = math.exp(-sigma * s["path"])
    L_ground = np.array(ALBEDO) / math.pi * synth.slab_irradiance(E_SLAB, sigma, s["path"], s["z_mid"], s["A"])
    expected = E_SLAB / sigma * (1 - T) + T * L_ground
    fig = check_uniform(a, b, expected, 1 - T, "absorbing slab")
    print("slab, absorbing:", fig, "render s", secs)


@pytest.mark.parametrize("lighting", ["lights", "paths"])
def test_far_slab_lights_match_paths_and_oracle(far_slab, tmp_path, cycles_render, compare, lighting):
    """A slab 100 km up (an aurora's height), 200 km wide, weakly absorbing:
    the default terrain lighting (clustered point lights, emission_lights.py)
    and brute-force diffuse bounces must both give the exact irradiance.
    Clusters are 4 voxels (4 km) 100 km away: point error ~(4/100)^2 / 12."""
    h, n_z = 1.0, 2
    sigma = 0.05
    vdb = far_slab
    scene = synth.write_scene(tmp_path / "c.toml", down_camera(10.0), 8, 8, spp=16, density_scale=sigma,
                              terrain={"kind": "plane", "height": 0.0, "albedo": list(ALBEDO)})
    a, b, secs = render_pair(cycles_render, compare, scene, vdb, tmp_path, 128, "c-" + lighting,
                             terrain_lighting=lighting)
    E = synth.slab_irradiance(E_SLAB, sigma, n_z * h, 100.5, 100.0)
    expected = np.array(ALBEDO) / math.pi * E
    # Relative bias allowed: 0.3% (point clusters and their self-attenuation,
    # see emission_lights.py; zero in "paths" mode, allowed for symmetry).
    fig = check_uniform(a, b, expected, 0.0, f"far slab, {lighting}", rel_bias=0.003)
    print(f"far slab, {lighting}:", fig, "render s", secs)
