"""The picture's development in Cycles, as `aurora render` develops its PNG
(src/render/develop.rs): the camera's white balance, then the exposure, then
the view transform.

- White balance (`[colour] white_balance_k`, camera observer only): the
  same 3x3 matrix as aurora's (src/util/white_balance.rs), computed here
  from the camera table the binary compiles in (camera_observer.json,
  checked against the binary by tests/render/sky_colour.rs). Blender 5's own
  colour-management white balance cannot give it: it adapts a white point
  by von Kries in a fixed cone space of XYZ, while the camera balances in
  its own raw space (the matrix's basis), so the two agree on the grey and
  differ on saturated light such as the green line. The matrix goes into
  the compositor instead: the render's Image plus its Environment pass (the
  sky behind a transparent film, render_settings.py), each output channel
  a dot product of the input with a row. The render passes (Combined,
  Environment) stay linear and unbalanced, as `aurora render`'s EXR.
- Exposure: the view's exposure (`view_settings.exposure`) is
  `render.exposure`, or for "auto" the EV `aurora render` meters
  ([`metered_ev`]: the reference renderer's image at a quarter of the size).
"""

from __future__ import annotations

import json
import math
import re
import subprocess
import tempfile
from pathlib import Path

import bpy

_TABLE = json.loads((Path(__file__).resolve().parent / "camera_observer.json").read_text())
#: The second radiation constant, nm K.
HC_K_NM = 1.438777e7
LUMA = (0.2126, 0.7152, 0.0722)


def _planck(lam: float, t_k: float) -> float:
    return lam ** -5 / math.expm1(HC_K_NM / (lam * t_k))


def _inverse(m):
    c = [[m[(r + 1) % 3][(k + 1) % 3] * m[(r + 2) % 3][(k + 2) % 3] - m[(r + 1) % 3][(k + 2) % 3] * m[(r + 2) % 3][(k + 1) % 3]
          for k in range(3)] for r in range(3)]
    det = sum(m[0][k] * c[0][k] for k in range(3))
    return [[c[j][i] / det for j in range(3)] for i in range(3)]


def _mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def white_balance_matrix(t_k: float):
    """W(T) of src/util/white_balance.rs: k N M diag(1 / U_T) M^-1, rows."""
    m = _TABLE["matrix"]
    grey = [0.0, 0.0, 0.0]
    for i, rgb in enumerate(_TABLE["rgb"]):
        p = _planck(_TABLE["first_nm"] + i, t_k)
        for c in range(3):
            grey[c] += p * rgb[c]
    m_inv = _inverse(m)
    u = [sum(m_inv[i][k] * grey[k] for k in range(3)) for i in range(3)]
    gains = [[1.0 / u[0], 0, 0], [0, 1.0 / u[1], 0], [0, 0, 1.0 / u[2]]]
    n = [[1.0 / sum(m[i]) if i == j else 0.0 for j in range(3)] for i in range(3)]
    k = sum(LUMA[c] * grey[c] for c in range(3))
    w = _mul(_mul(_mul(n, m), gains), m_inv)
    return [[x * k for x in row] for row in w]


def metered_ev(scene_toml, vdb, binary: str | None = None) -> float:
    """The EV `aurora render` meters for `render.exposure = "auto"` on the
    scene with the bake `vdb`, rendered at a quarter of its size, one sample
    a pixel (src/render/develop.rs: the meter reads a high percentile, which
    the size barely moves)."""
    from .bake_job import find_binary
    from .scene_toml import load_scene

    spec = load_scene(scene_toml)
    w, h = max(4, spec.render.width // 4), max(4, spec.render.height // 4)
    with tempfile.TemporaryDirectory(prefix="aurora-meter-") as tmp:
        cmd = [binary or find_binary(), "render", str(scene_toml), "--vdb", str(vdb), "--png", str(Path(tmp) / "m.png"),
               "--size", f"{w}x{h}", "--spp", "1"]
        r = subprocess.run(cmd, stdin=subprocess.DEVNULL, capture_output=True, text=True)
    found = re.search(r"exposure: auto, metered ([-+0-9.]+) EV", r.stderr)
    if r.returncode != 0 or found is None:
        raise ValueError(f"{scene_toml}: `aurora render` did not meter ({r.returncode}): {r.stderr.strip()}")
    return float(found.group(1))


def develop(scene: bpy.types.Scene, spec, ev: float | None = None) -> None:
    """Sets `scene`'s view exposure and the compositor's white balance as
    `aurora render` develops its PNG (module doc). ev: the EV for
    `render.exposure = "auto"` (metered_ev); a fixed exposure needs none."""
    exposure = spec.render.exposure
    if exposure == "auto":
        if ev is None:
            raise ValueError("render.exposure = \"auto\": give the metered EV (display.metered_ev)")
        exposure = ev
    scene.view_settings.exposure = float(exposure)
    scene.view_settings.use_white_balance = False
    matrix = white_balance_matrix(spec.white_balance_k) if spec.observer == "camera" else None
    scene["aurora_white_balance"] = [list(r) for r in matrix] if matrix else "none (eye observer)"
    scene["aurora_exposure_ev"] = float(exposure)
    tree = bpy.data.node_groups.new("AuroraDevelop", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    layers = tree.nodes.new("CompositorNodeRLayers")
    layers.scene = scene
    out = tree.nodes.new("NodeGroupOutput")
    # The sky behind a transparent film is in the Environment pass: added back.
    add = tree.nodes.new("ShaderNodeVectorMath")
    add.operation = "ADD"
    tree.links.new(layers.outputs["Image"], add.inputs[0])
    tree.links.new(layers.outputs["Environment"], add.inputs[1])
    # Opaque, as `aurora render`'s PNG (its alpha is not encoded).
    combine = tree.nodes.new("CompositorNodeCombineColor")
    rows = matrix or [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    for c, name in enumerate(("Red", "Green", "Blue")):
        dot = tree.nodes.new("ShaderNodeVectorMath")
        dot.operation = "DOT_PRODUCT"
        dot.inputs[1].default_value = rows[c]
        tree.links.new(add.outputs["Vector"], dot.inputs[0])
        tree.links.new(dot.outputs["Value"], combine.inputs[name])
    tree.links.new(combine.outputs["Image"], out.inputs[0])
    scene.compositing_node_group = tree
    scene.render.use_compositing = True
