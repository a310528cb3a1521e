"""docs/guide.md's Blender scripts, run as written.

The headless install block installs the zip `tools/build_extension` writes
(from a folder holding `dist/`, as the guide says: the clone's); a new
process then runs the guide's read-preferences block and the bake script,
in a saved .blend with a Curve object named "Ridge" (the one thing the
script assumes). Each process has a throw-away Blender user folder of its
own, so nothing but the preferences the install wrote carries over.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from scenes import aurora_bin

ROOT = Path(__file__).resolve().parent.parent.parent


def guide_blocks() -> list[str]:
    """The ```python blocks of docs/guide.md's "## Blender" section."""
    text = (ROOT / "docs" / "guide.md").read_text()
    section = text.split("\n## Blender\n", 1)[1].split("\n## ", 1)[0]
    return re.findall(r"```python\n(.*?)```", section, re.S)


def the_block(blocks: list[str], word: str) -> str:
    found = [b for b in blocks if word in b]
    assert len(found) == 1, f"docs/guide.md's Blender section has {len(found)} python blocks with {word!r}"
    return found[0]


def run(script: str, cwd: Path, env: dict) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", script], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


RIDGE = """
import bpy
curve = bpy.data.curves.new("Ridge", "CURVE")
spline = curve.splines.new("POLY")
spline.points.add(2)
for p, (x, y) in zip(spline.points, [(-60.0, 20.0), (0.0, 40.0), (60.0, 30.0)]):
    p.co = (x, y, 0.0, 1.0)
bpy.context.scene.collection.objects.link(bpy.data.objects.new("Ridge", curve))
bpy.ops.wm.save_as_mainfile(filepath="shot.blend")
"""


def test_the_guides_headless_install_and_bake_script_run_as_written(tmp_path):
    blocks = guide_blocks()
    install, reopen, bake = (the_block(blocks, w) for w in ("package_install_files", "read_userpref", "output_dir"))
    built = subprocess.run([sys.executable, str(ROOT / "tools" / "build_extension"), "--binary", str(aurora_bin()),
                            "--out", str(tmp_path / "dist")], capture_output=True, text=True)
    assert built.returncode == 0, built.stderr
    assert Path(built.stdout.strip()).name in install, "the guide installs the zip tools/build_extension writes"
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "user"))
    env.pop("AURORA_BIN", None)  # the zip's own baker
    first = run(install, tmp_path, env)
    assert first.returncode == 0, first.stdout + first.stderr
    module = "bl_ext.user_default.aurora_importer"
    check = f"\nassert {module!r} in bpy.context.preferences.addons, 'the extension is not enabled'\n"
    then = reopen + check + RIDGE + bake + "\nassert (Path('aurora_bake') / 'aurora.vdb').is_file()\n"
    second = run("from pathlib import Path\n" + then, tmp_path, env)
    assert second.returncode == 0, second.stdout + second.stderr
    assert "does not support blend relative" not in second.stderr, second.stderr
    assert (tmp_path / "aurora_bake" / "scene.toml").is_file()
