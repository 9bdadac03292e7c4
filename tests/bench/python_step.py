#!/usr/bin/env python3
"""The cost of calling a fit from Python: `tunekit.step` on bench_liquefier's 100k-sample FOPDT
record against the same compute_step() called from C++ (bench_step_command), in CPU time, in
alternating rounds (the machine may be busy: each round measures both under the same load).

    build/tests/bench/bench_liquefier --write-step /tmp/fopdt_step.csv
    PYTHONPATH=build/python python3 tests/bench/python_step.py /tmp/fopdt_step.csv \\
        build/tests/bench/bench_step_command [--rounds 9]

Prints the "BENCH python_step_cpu", "BENCH cpp_step_cpu" and "BENCH python_step_ratio" lines
scripts/bench reads (the ratio: Python's median CPU time over C++'s; the target is 1.10 at most).
"""

import argparse
import re
import subprocess
import time

import tunekit


def truth(path):
    """(t_step_s, du) from the record's comment line."""
    with open(path, encoding="ascii") as f:
        head = f.readline()
    values = dict(re.findall(r"(\w+)=(\S+)", head))
    return float(values["t_step_s"]), float(values["du"])


def cpp_round(bench, path, t_step, du, runs):
    r = subprocess.run([bench, path, repr(t_step), repr(du), str(runs)], capture_output=True, text=True, check=True)
    for line in r.stdout.splitlines():
        m = re.match(r"BENCH cpp_step_command_cpu median=(\S+)", line)
        if m:
            return float(m.group(1))
    raise SystemExit(f"{bench} printed no BENCH line:\n{r.stdout}")


def python_round(path, t_step, du, runs):
    times = []
    for _ in range(runs):
        c0 = time.process_time()
        tunekit.step(path, output="y", step_time=t_step, step_size=du, model="fopdt")
        times.append(1e3 * (time.process_time() - c0))
    return sorted(times)[len(times) // 2]


def bench_line(key, values, unit):
    v = sorted(values)
    print(f"BENCH {key} median={v[len(v) // 2]:.3f} min={v[0]:.3f} max={v[-1]:.3f} unit={unit} runs={len(v)}")


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("record")
    parser.add_argument("bench_step_command")
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--runs", type=int, default=3, help="timed calls per round and side (median)")
    args = parser.parse_args()
    t_step, du = truth(args.record)
    python_round(args.record, t_step, du, 1)  # warm-up
    py, cpp = [], []
    for _ in range(args.rounds):
        cpp.append(cpp_round(args.bench_step_command, args.record, t_step, du, args.runs))
        py.append(python_round(args.record, t_step, du, args.runs))
    ratios = [p / c for p, c in zip(py, cpp)]
    print(f"tunekit.step from Python: median CPU {sorted(py)[len(py) // 2]:.2f} ms; compute_step from C++: "
          f"{sorted(cpp)[len(cpp) // 2]:.2f} ms; per-round ratio median {sorted(ratios)[len(ratios) // 2]:.3f}")
    bench_line("python_step_cpu", py, "ms")
    bench_line("cpp_step_cpu", cpp, "ms")
    bench_line("python_step_ratio", ratios, "x")


if __name__ == "__main__":
    main()
