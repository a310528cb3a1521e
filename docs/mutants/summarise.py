#!/usr/bin/env python3
"""Summarise a cargo-mutants run for docs/mutants/REPORT.md.

usage: summarise.py OLD_TESTS MUTANTS_OUT...

MUTANTS_OUT: mutants.out directories of `tools/mutants` (one per shard),
summed; OLD_TESTS: a file of test names (one a line) that existed before the
report's tests were added.
For every mutant: its outcome, and for a caught one whether a test of
OLD_TESTS failed too (then the suite before the additions caught it) or only
added tests did (then it survived the old suite and names the tests that now
kill it). libtest runs every selected test, so a log lists all failures.
"""
import collections
import json
import pathlib
import re
import sys

old = set(pathlib.Path(sys.argv[1]).read_text().split())
rows = []
outcomes = []
for d in sys.argv[2:]:
    out = pathlib.Path(d)
    outcomes += [(out, o) for o in json.loads((out / "outcomes.json").read_text())["outcomes"]]
for out, o in outcomes:
    if o["scenario"] == "Baseline":
        continue
    m = o["scenario"]["Mutant"]
    name = f'{m["file"]}:{m["span"]["start"]["line"]}:{m["span"]["start"]["column"]}: {m["name"] if "name" in m else ""}'
    log = (out / o["log_path"]).read_text(errors="replace")
    name = log.splitlines()[1].removeprefix("*** ").strip()
    failed = re.findall(r"^test (\S+) \.\.\. FAILED", log, re.M)
    summary = o["summary"]
    if summary == "CaughtMutant":
        status = "caught (old suite)" if any(t in old for t in failed) else "caught (new tests only)"
    else:
        status = {"MissedMutant": "missed", "Timeout": "timeout", "Unviable": "unviable"}.get(summary, summary)
    rows.append((m["file"], name, status, [t for t in failed if t not in old]))

counts = collections.defaultdict(collections.Counter)
for f, _, s, _ in rows:
    counts[f][s] += 1
keys = ["caught (old suite)", "caught (new tests only)", "missed", "timeout", "unviable"]
print("| file | " + " | ".join(keys) + " | total |")
print("|---" * (len(keys) + 2) + "|")
for f in sorted(counts):
    print(f"| {f} | " + " | ".join(str(counts[f][k]) for k in keys) + f" | {sum(counts[f].values())} |")
tot = collections.Counter()
for c in counts.values():
    tot.update(c)
print("| all | " + " | ".join(str(tot[k]) for k in keys) + f" | {sum(tot.values())} |")
print()
for f, name, s, new in sorted(rows):
    if s != "caught (old suite)":
        names = [t.split("::")[-1] for t in new]
        short = ", ".join(f"`{n}`" for n in names[:2]) + (f" (+{len(names) - 2})" if len(names) > 2 else "")
        print(f"- `{name}`: {s}" + (f"; killed by {short}" if new and s.startswith("caught") else ""))
