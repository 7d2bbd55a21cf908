#!/usr/bin/env python3
"""Writes a generated static IMU as a EuRoC CSV: six axes at 400 Hz, white noise and a random
walk about a mean (gravity on z), stamps in ns with a jitter of up to 20 us.

    python3 tools/static-imu-csv.py OUT.csv SAMPLES SEED

The recordings of tools/characterise-bench.sh and tools/csv-versus-pandas.sh.
"""
import sys

import numpy as np

out, n, seed = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rng = np.random.default_rng(seed)
dt = 1 / 400
t = 1_700_000_000_000_000_000 + np.arange(n, dtype=np.int64) * 2_500_000 \
    + rng.integers(-20_000, 20_001, n)
white = np.array([1e-3, 1.2e-3, 0.8e-3, 2e-2, 2.5e-2, 3e-2]) / np.sqrt(dt)
walk = np.array([2e-5, 1e-5, 3e-5, 4e-4, 2e-4, 5e-4]) * np.sqrt(dt)
mean = np.array([0.01, -0.02, 0.005, 0.1, -0.2, 9.81])
x = mean + white * rng.standard_normal((n, 6)) + np.cumsum(walk * rng.standard_normal((n, 6)), 0)
with open(out, "w") as f:
    f.write("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
            "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n")
    step = 200_000
    for i in range(0, n, step):
        block = np.column_stack([t[i:i + step].astype(object), x[i:i + step]])
        f.write("\n".join(",".join([str(r[0])] + [repr(float(v)) for v in r[1:]]) for r in block))
        f.write("\n")
