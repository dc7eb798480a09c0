#!/usr/bin/python3
"""numpy baseline: octave overlapping ADEV by cumulative sum (the usual textbook code).

Reads the CSV with pandas (timed separately), then times only the in-memory part:
phase = cumsum(y - mean) * tau0 with a leading 0, and for m = 1, 2, 4, ... <= M/4
sigma^2 = sum((x[2m:] - 2 x[m:-m] + x[:-2m])^2) / (2 tau^2 (N - 2m)).
Usage: /usr/bin/python3 numpy_oadev.py FILE.csv [TAU0_S]
"""
import sys
import time

import numpy as np
import pandas as pd


def main():
    path = sys.argv[1]
    tau0 = float(sys.argv[2]) if len(sys.argv) > 2 else 0.01
    t0 = time.perf_counter()
    y = pd.read_csv(path).iloc[:, 0].to_numpy(dtype=np.float64)
    t1 = time.perf_counter()
    x = np.concatenate(([0.0], np.cumsum(y - y.mean()) * tau0))
    n = x.size
    taus, devs = [], []
    m = 1
    while m <= y.size // 4:
        d = x[2 * m:] - 2.0 * x[m:-m] + x[:-2 * m]
        tau = m * tau0
        devs.append(np.sqrt(np.dot(d, d) / (2.0 * tau * tau * (n - 2 * m))))
        taus.append(tau)
        m *= 2
    t2 = time.perf_counter()
    for tau, dev in zip(taus, devs):
        print(f"{tau:.6g},{dev:.6g}")
    print(f"numpy: {y.size} samples, {len(taus)} taus: pandas read {t1 - t0:.3f} s, "
          f"in-memory OADEV {t2 - t1:.3f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
