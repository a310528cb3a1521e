"""The scene files the studies run, each written beside its outputs: the
default preset as the mode edits it, the writer study's full-float layout,
one file per gather method, the dome master's preset, and each render
case's view of the bake (with its reference at sub-pixels)."""

from __future__ import annotations

import re
from pathlib import Path

from aurora_tools.files import write_atomic
from aurora_tools.toml_io import edit_toml
from runners import Failure, Tools, run
from settings import F32_LAYOUT


def default_scene(tools: Tools, cfg: dict, out: Path):
    """The default preset with the mode's `scene_edits`: its text, and what
    `aurora bake` is given (the preset's name, or the edited file in `out`)."""
    scene_text = run([tools.aurora, "scene", "default"], "aurora scene default").stdout
    if cfg["scene_edits"]:
        scene_text = edit_toml(scene_text, cfg["scene_edits"])
        scene_arg = out / "scene.toml"
        write_atomic(scene_arg, scene_text.encode())
    else:
        scene_arg = "default"
    return scene_text, scene_arg


def f32_scene(scene_text: str, out: Path) -> Path:
    """The writer study compares writers on full-float grids, one per field
    (the C++ tool rewrites what it reads): the scene with that layout
    (F32_LAYOUT), not the default's half floats and high column."""
    path = out / "scene-f32.toml"
    write_atomic(path, edit_toml(scene_text, F32_LAYOUT).encode())
    return path


def gather_scenes(scene_text: str, d: Path, methods) -> dict:
    """The scene once per `[photons] gather` method, in `d`."""
    scenes = {}
    for m in methods:
        p = d / f"{m}.toml"
        write_atomic(p, edit_toml(scene_text, {("photons", "gather"): m}).encode())
        scenes[m] = p
    return scenes


def dome_scene(tools: Tools, dome: dict, d: Path):
    """The dome case's preset (a fisheye camera) at its size with its
    `scene_edits`: its text and its file in `d`."""
    w, h = dome["size"]
    text = run([tools.aurora, "scene", dome["preset"]], f"aurora scene {dome['preset']}").stdout
    cam = text.split("[camera]", 1)[1]
    if not re.search(r'(?m)^projection\s*=\s*"fisheye"', cam.split("\n[", 1)[0]):
        raise Failure(f"the {dome['preset']} preset's camera is not a fisheye")
    text = edit_toml(text, {**dome["scene_edits"], ("render", "width"): w, ("render", "height"): h})
    scene = d / "bake-scene.toml"
    write_atomic(scene, text.encode())
    return text, scene


def case_scene(scene_text: str, case: str, w: int, h: int, d: Path) -> Path:
    """The render case's scene in `d`, at w x h with [render] spp > 1, so
    both renderers average over the pixel square (box)."""
    # As tests/python/test_cross_check.py: no terrain, or a plane with the
    # camera's look-at lowered to 40 km so the ground fills the lower third
    # (and no air).
    edits = {("render", "width"): w, ("render", "height"): h, ("render", "spp"): 16}
    if case == "volume":
        edits[("terrain", "kind")] = "none"
    elif case == "dome":
        # The preset as baked (its camera, air and ground) without the
        # stars and the airglow: the volume's cost at equal error is what
        # this case measures. Cycles reads the sky from `aurora sky`'s map,
        # whose resampling at 64 px is a floor of about 0.4 % that would
        # stall the error ladder; test_cross_check compares the sky itself.
        edits[("background", "stars")] = False
        edits[("airglow", "on")] = False
    else:
        edits[("terrain", "kind")] = "plane"
        cam = re.search(r"(?m)^look_at\s*=\s*\[([^\]]*)\]", scene_text.split("[camera]", 1)[1])
        x, y, _ = (float(v) for v in cam.group(1).split(","))
        edits[("camera", "look_at")] = [x, y, 40.0]
        # The add-on dims the volume's emission by the air, not the
        # terrain's light (blender/air.py): compare the lighting alone.
        edits[("sky", "extinction")] = False
    scene = d / "scene.toml"
    write_atomic(scene, edit_toml(scene_text, edits).encode())
    return scene


def reference_scene(scene: Path, w: int, h: int, f: int, d: Path) -> Path:
    """The case's scene at f x f sub-pixels a pixel (the reference renders it
    and averages f x f blocks); the scene itself when f is 1."""
    if f <= 1:
        return scene
    ref_scene = d / "reference-scene.toml"
    write_atomic(ref_scene, edit_toml(scene.read_text(), {("render", "width"): w * f,
                                                          ("render", "height"): h * f}).encode())
    return ref_scene
