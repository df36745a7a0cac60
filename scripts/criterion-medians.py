#!/usr/bin/env python3
"""Print the median of every criterion benchmark under target/criterion as a Markdown table.

Usage: python3 scripts/criterion-medians.py [FILTER]
"""
import json
import pathlib
import sys

root = pathlib.Path(__file__).resolve().parent.parent / "target" / "criterion"
flt = sys.argv[1] if len(sys.argv) > 1 else ""
rows = []
for est in sorted(root.glob("**/new/estimates.json")):
    bench = json.loads((est.parent / "benchmark.json").read_text())
    name = bench["full_id"]
    if flt not in name:
        continue
    med = json.loads(est.read_text())["median"]["point_estimate"]
    rows.append((name, med))
print("| benchmark | median |")
print("|---|---|")
for name, ns in rows:
    val = f"{ns:.0f} ns" if ns < 1e4 else f"{ns / 1e3:.1f} µs"
    print(f"| {name} | {val} |")
