#!/usr/bin/env python3
"""A linear EXR through Blender's own AgX view for an sRGB display, as an 8-bit PNG.

    .venv/bin/python tools/cycles/agx_png.py IMAGE.exr IMAGE.png [--exposure STOPS] [--white-balance-k K] [--look LOOK | --view WORD]

Blender's colour management (display sRGB, view AgX, look None or LOOK such
as "AgX - Punchy", no dither), the view `aurora render` builds for its PNGs (docs/guide.md, "Rendering"), so
a Cycles render and an `aurora render` PNG of the same scene are shown alike.
--view takes a scene's `render.view_transform` word instead ("agx_punchy",
"standard", ...), shown through the view and look the add-on sets for it
(blender/render_settings.py, `blender_view`).
With --white-balance-k the EXR is first developed as `aurora render`
develops its PNG for the camera observer (the camera's white balance, the
add-on's matrix: blender/display.py, docs/colour.md).
The PNG is written to a temporary name in the output folder and renamed, so
a reader never sees a half-written picture.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tools/: the shared package aurora_tools
from aurora_tools.files import replace_atomic  # noqa: E402


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("exr", help="linear OpenEXR (RGB or RGBA)")
    p.add_argument("png", help="output PNG")
    p.add_argument("--exposure", type=float, default=0.0, help="stops, as [render] exposure (default 0)")
    shown = p.add_mutually_exclusive_group()
    shown.add_argument("--look", default="None", help='Blender\'s look for AgX, as render.view_transform "agx_punchy" is "AgX - Punchy" (default None)')
    shown.add_argument("--view", default=None, help='a render.view_transform word ("agx", "agx_punchy", "standard", ...): the view and look the add-on sets for it')
    p.add_argument("--white-balance-k", type=float, default=None,
                   help="the camera's white balance, K, as [colour] white_balance_k (default: the EXR as it is)")
    a = p.parse_args(argv)
    if not Path(a.exr).is_file():
        print(f"agx_png: error: {a.exr}: no such file", file=sys.stderr)
        return 2
    import bpy

    import tempfile

    tmp_dir = tempfile.TemporaryDirectory(prefix="agx_png.")
    exr = Path(a.exr).resolve()
    if a.white_balance_k is not None:
        import numpy as np
        from aurora_tools.addon import load_addon
        from aurora_tools.exr_io import read_rgba, write_rgba_exr

        rgba = read_rgba(exr)
        rgba[..., :3] = rgba[..., :3] @ np.asarray(load_addon().display.white_balance_matrix(a.white_balance_k)).T
        exr = Path(tmp_dir.name) / "developed.exr"
        write_rgba_exr(exr, rgba.astype(np.float32))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    img = bpy.data.images.load(str(exr))
    sc = bpy.context.scene
    sc.display_settings.display_device = "sRGB"
    vs = sc.view_settings
    view, look = "AgX", a.look
    if a.view is not None:
        from aurora_tools.addon import load_addon

        try:
            view, look = load_addon().render_settings.blender_view(a.view)
        except ValueError as e:
            print(f"agx_png: error: --view: {e}", file=sys.stderr)
            return 2
    vs.view_transform, vs.exposure, vs.gamma = view, a.exposure, 1.0
    try:
        vs.look = look
    except TypeError:
        print(f"agx_png: error: --look {look!r} is not one of Blender's looks for {view}", file=sys.stderr)
        return 2
    sc.render.dither_intensity = 0.0
    s = sc.render.image_settings
    s.file_format, s.color_mode, s.color_depth = "PNG", "RGB", "8"

    def save(tmp: str) -> None:
        img.save_render(tmp, scene=sc)
        if os.path.getsize(tmp) == 0:
            raise RuntimeError(f"Blender wrote nothing to {tmp}")

    replace_atomic(Path(a.png).resolve(), save, suffix=".tmp.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
