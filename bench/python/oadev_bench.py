#!/usr/bin/python3
"""In-process octave OADEV of 10^7 rate samples: metro.allan against allantools-style numpy.

The baseline is allantools' own algorithm (allantools 2019.9, allantools.py: frequency2phase,
then calc_adev_phase at stride 1 for each m of the octave list), written out here with numpy so
that no package outside Debian is needed:
    phase = [0, cumsum(y - mean(y)) * tau0]
    for m = 1, 2, 4, ... <= M / 4:
        v = phase[2m:] - 2 phase[m:-m] + phase[:-2m]
        oadev(m tau0) = sqrt(sum(v^2) / (2 (N - 2m))) / (m tau0)
metro.allan does that and more in each run: the lag-1 noise identification at every tau, the
Greenhall-Riley EDF and the chi-squared intervals (NIST SP 1065 5.3.2), and the IEEE 952
noise-term fit. Both read the same float64 array in the same interpreter; metro's input is
checked not to be copied (the address it read equals the array's).

Runs each RUNS times, alternating, and prints the median, min and max of each, the ratio of the
medians and the largest relative difference of the two curves.
Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/oadev_bench.py [N=1e7] [RUNS=5]
"""
import os
import statistics
import sys
import time

import numpy as np

import metro


def allantools_style_oadev(y, tau0):
    phase = np.insert(np.cumsum(y - np.nanmean(y)) * tau0, 0, 0.0)
    n = phase.size
    taus, devs = [], []
    m = 1
    while m <= y.size // 4:
        d2 = phase[2 * m:]
        d1 = phase[m:]
        d0 = phase
        k = min(d0.size, d1.size, d2.size)
        v = d2[:k] - 2 * d1[:k] + d0[:k]
        s = np.sum(v * v)
        devs.append(np.sqrt(s / (2.0 * k)) / (m * tau0))
        taus.append(m * tau0)
        m *= 2
    return np.array(taus), np.array(devs)


def main():
    n = int(float(sys.argv[1])) if len(sys.argv) > 1 else 10_000_000
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 5
    tau0 = 0.01
    rng = np.random.default_rng(1)
    # White rate noise plus a random walk of the rate: a gyroscope's N and K.
    y = 0.02 * rng.standard_normal(n) + np.cumsum(1e-5 * rng.standard_normal(n)) + 0.3
    print(f"N = {n}, {runs} runs each, alternating; load average "
          f"{' '.join(open('/proc/loadavg').read().split()[:3])}; {os.cpu_count()} cores")
    metro_s, numpy_s, metro_cpu, numpy_cpu = [], [], [], []
    for _ in range(runs):
        c0, t0 = time.process_time(), time.perf_counter()
        a = metro.allan(y, tau0, unit="deg/s")
        c1, t1 = time.process_time(), time.perf_counter()
        taus, devs = allantools_style_oadev(y, tau0)
        c2, t2 = time.process_time(), time.perf_counter()
        metro_s.append(t1 - t0)
        numpy_s.append(t2 - t1)
        metro_cpu.append(c1 - c0)
        numpy_cpu.append(c2 - c1)
    assert a.input_address == y.__array_interface__["data"][0], "metro copied its input"
    assert np.array_equal(a.tau_s, taus)
    rel = np.max(np.abs(a.adev - devs) / devs)
    print(f"load average after: {' '.join(open('/proc/loadavg').read().split()[:3])}")
    for name, t, cpu in (("metro.allan (OADEV + EDF + intervals + IEEE 952 fit)", metro_s, metro_cpu),
                         ("allantools-style numpy OADEV", numpy_s, numpy_cpu)):
        print(f"{name}: median {statistics.median(t):.3f} s wall, min {min(t):.3f} s, "
              f"max {max(t):.3f} s; median {statistics.median(cpu):.3f} s CPU (all threads)")
    print(f"ratio of the medians: {statistics.median(numpy_s) / statistics.median(metro_s):.1f} x")
    print(f"zero copy: metro read the array at its own address (0x{a.input_address:x})")
    print(f"curves: {taus.size} taus, largest relative difference {rel:.2e}")


if __name__ == "__main__":
    main()
