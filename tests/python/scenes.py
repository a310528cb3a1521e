"""The small scene the add-on's tests bake, and the binary that bakes it.

`SMALL` bakes in about a second a frame on two cores: one curtain, a coarse
footprint, 400 beams, 1 km voxels. A test adds its own keys with
`write_small_scene(path, table={key: value, ...})`.

The binary is $AURORA_BIN or target/release/aurora (a missing binary fails
the test).
"""

from __future__ import annotations

import copy
import os
from pathlib import Path

import synth

ROOT = Path(__file__).resolve().parents[2]

SMALL = {
    "seed": 7,
    "curtain": [{"center": [0.0, 0.0], "length": 40.0, "width": 12.0, "bend_km": 3.0}],
    "footprint": {"resolution": [96, 32], "steps": 4},
    "beams": {"count": 400},
    "photons": {"radius_km": 0.8},
    "grid": {"voxel_size": 1.0},
}


def small_scene(**tables) -> dict:
    """SMALL with `tables` merged in: a table's keys are added to SMALL's
    table of that name (or replace them); anything else replaces the key."""
    doc = copy.deepcopy(SMALL)
    for name, value in tables.items():
        doc[name] = {**doc.get(name, {}), **value} if isinstance(value, dict) else value
    return doc


def write_small_scene(path, **tables) -> Path:
    """`small_scene(**tables)` written to `path` as TOML."""
    Path(path).write_text(synth.toml_dumps(small_scene(**tables)))
    return Path(path)


def aurora_bin() -> Path:
    """The aurora executable the tests run."""
    p = Path(os.environ.get("AURORA_BIN", ROOT / "target" / "release" / "aurora"))
    assert p.is_file() and os.access(p, os.X_OK), f"{p}: the aurora binary is missing (cargo build --release)"
    return p.resolve()
