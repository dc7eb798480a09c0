#!/usr/bin/python3
"""Summarises side-by-side benchmark runs: median, min and max of each contender and the
ratio of the medians.

Usage: compare_times.py "METRO LABEL" "t1 t2 ..." "BASELINE LABEL" "t1 t2 ..."  (seconds)
"""
import statistics
import sys

metro_label, metro_times, base_label, base_times = sys.argv[1:5]
metro = [float(v) for v in metro_times.split()]
base = [float(v) for v in base_times.split()]
for name, v in ((metro_label, metro), (base_label, base)):
    print(f"{name}: median {statistics.median(v):.3f} s, min {min(v):.3f}, max {max(v):.3f} "
          f"({len(v)} runs)")
print(f"ratio of medians ({base_label.split()[0]} / {metro_label.split()[0]}): "
      f"{statistics.median(base) / statistics.median(metro):.1f}x")
