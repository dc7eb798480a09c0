# numpy baseline for the JCGM 101 9.5 gauge-block Monte Carlo (same model, inputs and 99 %
# shortest interval as bench_mc.cpp). Prints the in-process time (generator creation to
# interval). Usage: /usr/bin/python3 numpy_gauge_block.py [TRIALS]
import numpy as np, time, sys
M = int(float(sys.argv[1])) if len(sys.argv) > 1 else 10**7
t0 = time.perf_counter()
rng = np.random.default_rng(1)
def tdist(mu, s, nu): return mu + s * rng.standard_t(nu, M)
def ctrap(a, b, d):
    r1 = rng.random(M); r2 = rng.random(M)
    a_s = (a - d) + 2 * d * r1; b_s = (a + b) - a_s
    return a_s + (b_s - a_s) * r2
ls = tdist(50000623.0, 25.0, 18); D = tdist(215.0, 5.8, 24); D1 = tdist(0, 3.9, 5); D2 = tdist(0, 6.7, 8)
als = rng.uniform(9.5e-6, 13.5e-6, M); th0 = rng.normal(-0.1, 0.2, M)
Dl = 0.5 * np.sin(2 * np.pi * rng.random(M))
da = ctrap(-1e-6, 1e-6, 0.1e-6); dth = ctrap(-0.05, 0.05, 0.025)
y = ls + D + D1 + D2 - ls * (da * (th0 + Dl) + als * dth) - 50000000.0
mean = y.mean(); u = y.std(ddof=1)  # JCGM 101 7.6
ys = np.sort(y); q = int(0.99 * M + 0.5); w = ys[q:] - ys[:M - q]; r = int(np.argmin(w))
t1 = time.perf_counter()
print(f"numpy M={M} mean={mean:.3f} u={u:.3f} shortest=[{ys[r]:.2f}, {ys[r+q]:.2f}] time_s={t1-t0:.3f}")
