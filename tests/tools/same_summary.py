#!/usr/bin/env python3
"""Two runs' summary.json agree: the wire's tip, base force and inserted length, and the run's
status and step count (relative 1e-9; an MPI run's flow differs from one rank's by round-off).
usage: same_summary.py A/summary.json B/summary.json"""
import json
import sys

a, b = (json.load(open(p)) for p in sys.argv[1:3])
for key in ("status", "steps"):
    if a[key] != b[key]:
        sys.exit(f"{key}: {a[key]} != {b[key]}")
for key in ("tip", "base_force"):
    for x, y in zip(a["wire"][key], b["wire"][key]):
        if abs(x - y) > 1e-9 * max(1.0, abs(x), abs(y)):
            sys.exit(f"wire.{key}: {a['wire'][key]} != {b['wire'][key]}")
if abs(a["wire"]["inserted_length"] - b["wire"]["inserted_length"]) > 1e-12:
    sys.exit("wire.inserted_length differs")
print("same results")
