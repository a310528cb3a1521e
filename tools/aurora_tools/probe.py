"""The probes' shared start (tools/*_probe.py, run by the Rust tests): import
the reference library or print one JSON line naming it and exit 3, which
the test turns into a failure naming tools/setup (never a skip)."""

from __future__ import annotations

import importlib
import json
import sys


def require(module: str, what: str | None = None):
    """`importlib.import_module(module)`, or a JSON error line and exit 3."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        print(json.dumps({"error": f"{what or module} not importable: {e}; run tools/setup"}))
        sys.exit(3)
