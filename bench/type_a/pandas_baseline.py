#!/usr/bin/python3
"""Baseline for the Type A benchmark: pandas read_csv + groupby mean/var per tag.

Usage: pandas_baseline.py SESSION.csv
Prints the seconds spent in-process (read + groupby), excluding interpreter start-up.
"""
import sys
import time

import pandas as pd

start = time.perf_counter()
frame = pd.read_csv(sys.argv[1], comment="#")
stats = frame.groupby("sensor").agg(["mean", "var"])
elapsed = time.perf_counter() - start
print(f"pandas {pd.__version__}: {len(frame)} rows, {len(stats)} tags, {elapsed:.3f} s in-process")
