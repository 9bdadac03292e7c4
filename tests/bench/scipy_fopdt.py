#!/usr/bin/env python3
"""Times SciPy's curve_fit on the FOPDT step record the `fopdt_fit` benchmark row fits.

    build/tests/bench/bench_liquefier --write-step /tmp/fopdt_step.csv
    python3 tests/bench/scipy_fopdt.py /tmp/fopdt_step.csv [--runs 15]

The model is the one tunekit fits (Holtrup 2019 eq. 4.5-4.8):
y = y0 for t <= t_step + theta, y0 + K du (1 - exp(-(t - t_step - theta) / tau)) afterwards.
scipy.optimize.curve_fit (its default Levenberg-Marquardt, MINPACK, with the Jacobian by finite
differences) starts from the truth in the file's comment line moved by about 10 % (K and theta
up, tau and y0 down) and returns the parameters with their covariance. Timed in this process
after one untimed warm-up: median, fastest and slowest of --runs fits, printed as the
"BENCH scipy_curve_fit_fopdt ..." line that scripts/bench reads (tests/bench/bench_common.hpp).
Needs numpy and scipy (Debian: python3-scipy).
"""

import argparse
import re
import sys
import time

import numpy as np
import scipy
from scipy.optimize import curve_fit


def read_record(path):
    """(t, y, t_step, du, truth {K, tau_s, theta_s, y0}) from bench_liquefier's CSV."""
    with open(path, encoding="ascii") as f:
        head = f.readline()
    values = dict(re.findall(r"(\w+)=(\S+)", head))
    data = np.loadtxt(path, delimiter=",", comments="#", skiprows=2)
    truth = {k: float(values[k]) for k in ("K", "tau_s", "theta_s", "y0")}
    return data[:, 0], data[:, 1], float(values["t_step_s"]), float(values["du"]), truth


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("csv", help="the step record (bench_liquefier --write-step FILE)")
    parser.add_argument("--runs", type=int, default=15, help="timed fits (default 15)")
    args = parser.parse_args()
    t, y, t_step, du, truth = read_record(args.csv)

    def model(t, K, tau, theta, y0):
        s = np.maximum(t - t_step - theta, 0.0)
        return y0 + K * du * (1.0 - np.exp(-s / tau))

    start = [1.1 * truth["K"], 0.9 * truth["tau_s"], 1.1 * truth["theta_s"], 0.9 * truth["y0"]]

    def fit():
        return curve_fit(model, t, y, p0=start)

    fit()  # warm-up
    wall, cpu = [], []
    for _ in range(args.runs):
        w0, c0 = time.perf_counter(), time.process_time()
        p, cov = fit()
        cpu.append(1e3 * (time.process_time() - c0))
        wall.append(1e3 * (time.perf_counter() - w0))
    se = np.sqrt(np.diag(cov))
    wall.sort()
    cpu.sort()
    median = wall[len(wall) // 2]
    print(f"scipy {scipy.__version__} curve_fit FOPDT on {len(t)} samples: median wall {median:.2f} ms, "
          f"median cpu {cpu[len(cpu) // 2]:.2f} ms (start {', '.join(f'{v:.4g}' for v in start)})")
    for name, v, e in zip(("K", "tau_s", "theta_s", "y0"), p, se):
        print(f"  {name} {v:.6g} +- {e:.2g}")
    print(f"BENCH scipy_curve_fit_fopdt median={median:.3f} min={wall[0]:.3f} max={wall[-1]:.3f} unit=ms "
          f"runs={len(wall)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
