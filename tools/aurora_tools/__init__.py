"""aurora_tools: the Python package the scripts in tools/ and benchmarks/ share.

Modules:
- `exr_io`: read and write OpenEXR images (RGBA, multi-layer Cycles output);
- `toml_io`: edit a scene file printed by `aurora scene`, key by key;
- `png`: PNG files with zlib and numpy (read any 8/16-bit PNG, write RGB);
- `files`: atomic file writes (temporary name, then rename);
- `addon`: the Blender add-on in ../blender, loaded once under one name
  (`aurora_importer`), and its scene reader;
- `cycles`: a scene rendered by Blender Cycles through the add-on;
- `image_compare`: two renders' error figures and comparison picture;
- `blender_worker`: a long-lived bpy child process answering JSON requests;
- `probe`: the probes' shared start (import a module or print a JSON error).

How to import it: the package sits in tools/, so tools/ must be on
sys.path. A script in a folder of tools/ (tools/cycles/, tools/probes/,
tools/reference/) or of benchmarks/ puts it there in one line before its
first `from aurora_tools ...` import, since Python puts only the script's
own folder first on sys.path:

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

(benchmarks/ scripts name ROOT / "tools" instead). The pytest suite puts
tools/ on sys.path once, in tests/python/conftest.py. No script imports
another script by path.
"""

from pathlib import Path

#: The repository root.
ROOT = Path(__file__).resolve().parent.parent.parent
