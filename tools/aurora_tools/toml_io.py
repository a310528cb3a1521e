"""Scene files as text: set `key = value` in a section of what `aurora scene`
prints, keeping every other line (and comment) as it is."""

from __future__ import annotations

import json
import re


def toml_value(v) -> str:
    """A Python value as a TOML value (bool, int, float, str, lists of them)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"no TOML for {v!r}")


def edit_toml(text: str, edits: dict) -> str:
    """Set `key = value` in `[section]` of a scene file printed by `aurora
    scene`, keeping every other line as it is. edits: {(section, key): value}."""
    lines = text.splitlines()
    todo = dict(edits)
    section = None
    header_at = {}
    for i, line in enumerate(lines):
        s = line.strip()
        if s.startswith("["):
            section = s.strip("[]").strip()
            header_at.setdefault(section, i)
            continue
        m = re.match(r"\s*([A-Za-z0-9_]+)\s*=", line)
        if m and (section, m.group(1)) in todo:
            lines[i] = f"{m.group(1)} = {toml_value(todo.pop((section, m.group(1))))}"
    for (sec, key), v in todo.items():  # keys the file does not print
        if sec in header_at:
            lines.insert(header_at[sec] + 1, f"{key} = {toml_value(v)}")
            header_at = {k: (j + 1 if j > header_at[sec] else j) for k, j in header_at.items()}
        else:
            lines += ["", f"[{sec}]", f"{key} = {toml_value(v)}"]
            header_at[sec] = len(lines) - 2
    return "\n".join(lines) + "\n"
