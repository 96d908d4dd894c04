#!/usr/bin/env python3
"""Per-phase cost of a co-simulation step against the inserted wire length and the network's
sampling (the aortic-arch example, bench_coupling's BM_ArchScaling), with log-log slopes.

    python3 scripts/arch_scaling.py [build/bench/bench_coupling]   # prints a Markdown table
"""
import json
import math
import subprocess
import sys

bench = sys.argv[1] if len(sys.argv) > 1 else "build/bench/bench_coupling"
out = subprocess.run([bench, "--benchmark_filter=ArchScaling", "--benchmark_format=json"],
                     check=True, capture_output=True, text=True).stdout
phases = ["lookup_us", "contact_us", "drag_us", "assembly_us", "factorize_us", "line_search_us"]
rows = []
for b in json.loads(out)["benchmarks"]:
    args = dict(p.split(":") for p in b["name"].split("/")[1:] if ":" in p and not p.startswith("iterations"))
    rows.append({"cm": int(args["inserted_cm"]), "mm": int(args["network_tenth_mm"]) / 10,
                 "ms": b["real_time"], **{k: b[k] for k in phases + ["vertices", "segments", "newton_per_step",
                                                                   "unconverged"]}})

print("| inserted | network | vertices | segments | ms/step | " + " | ".join(p[:-3] + " µs" for p in phases) +
      " | Newton its | unconverged |")
print("|" + "---|" * (5 + len(phases) + 2))
for r in rows:
    print(f"| {r['cm']} cm | {r['mm']:g} mm | {r['vertices']:.0f} | {r['segments']:.0f} | {r['ms']:.3f} | " +
          " | ".join(f"{r[p]:.0f}" for p in phases) + f" | {r['newton_per_step']:.2f} | {r['unconverged']:.0f} |")


def slope(a, b, x):
    return lambda key: math.log(b[key] / a[key]) / math.log(b[x] / a[x])


by_len = sorted((r for r in rows if r["mm"] == 5.0), key=lambda r: r["cm"])
by_net = sorted((r for r in rows if r["cm"] == 78), key=lambda r: r["segments"])
print()
print("| log-log slope | ms/step | " + " | ".join(p[:-3] for p in phases) + " |")
print("|" + "---|" * (2 + len(phases)))
for label, a, b, x in (("against vertices (inserted length)", by_len[0], by_len[-1], "vertices"),
                       ("against segments (network sampling)", by_net[0], by_net[-1], "segments")):
    s = slope(a, b, x)
    print(f"| {label} | {s('ms'):.2f} | " + " | ".join(f"{s(p):.2f}" for p in phases) + " |")
