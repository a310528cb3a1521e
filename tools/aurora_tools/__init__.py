"""aurora_tools: the helpers the scripts in tools/ share.

Modules:
- `exr_io`: read and write OpenEXR images (RGBA, multi-layer Cycles output);
- `toml_io`: edit a scene file printed by `aurora scene`, key by key;
- `files`: atomic file writes (temporary name, then rename);
- `addon`: the Blender add-on in ../blender, loaded once under one name
  (`aurora_importer`), and its scene reader;
- `blender_worker`: a long-lived bpy child process answering JSON requests;
- `probe`: the probes' shared start (import a module or print a JSON error).

How to import it (the one way): a script in tools/ just says
`import aurora_tools` (or `from aurora_tools.x import y`): Python puts a
script's own folder first on sys.path, and this package sits in tools/.
Code elsewhere (the pytest suite) puts tools/ on sys.path once, in
tests/python/conftest.py. No script edits sys.path and no script imports
another script by path.
"""

from pathlib import Path

#: The repository root.
ROOT = Path(__file__).resolve().parent.parent.parent
#: tools/
TOOLS = ROOT / "tools"
