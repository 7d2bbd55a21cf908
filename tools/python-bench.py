#!/usr/bin/env python3
"""The Python package side by side with allantools, in one run: the overlapping Allan deviation
at octave averaging times and the noise model, on 10^7 generated samples (white noise plus a
random walk, seeded), best of three runs each. Prints a Markdown table.

    python tools/python-bench.py            # in a venv with the wheel, numpy and allantools
    python tools/python-bench.py --n 1000000
"""

import argparse
import os
import platform
import time

import numpy as np

import allantools
import imu_ar


def best(f, runs):
    times = []
    for _ in range(runs):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return min(times), out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10_000_000, help="samples [10^7]")
    ap.add_argument("--runs", type=int, default=3, help="runs of each, the best taken [3]")
    args = ap.parse_args()
    rate = 100.0
    rng = np.random.default_rng(2010)
    x = rng.normal(0.0, 0.05, args.n) + np.cumsum(rng.normal(0.0, 1e-4, args.n))

    t_ours, ours = best(lambda: imu_ar.adev(x, rate=rate, taus="octave"), args.runs)
    t_theirs, theirs = best(
        lambda: allantools.oadev(x, rate=rate, data_type="freq", taus="octave"), args.runs
    )
    t_noise, model = best(lambda: imu_ar.noise(x, rate=rate), args.runs)
    worst = float(np.max(np.abs(ours.devs / theirs[1] - 1.0)))

    print(f"{args.n} samples at {rate:g} Hz (white + random walk, seed 2010), best of "
          f"{args.runs}; {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}, allantools {allantools.__version__}\n")
    print("| call | time (s) | ratio |")
    print("| --- | ---: | ---: |")
    print(f"| `allantools.oadev(x, rate, data_type=\"freq\", taus=\"octave\")` | {t_theirs:.3f} | 1 |")
    print(f"| `imu_ar.adev(x, rate, taus=\"octave\")` | {t_ours:.3f} | {t_ours / t_theirs:.3f} |")
    print(f"| `imu_ar.noise(x, rate)` | {t_noise:.3f} | |")
    print(f"\n{len(ours.devs)} octaves; largest relative difference from allantools "
          f"{worst:.1e}; N = {model.white_noise:.4g}, K = {model.random_walk:.4g}")


if __name__ == "__main__":
    main()
