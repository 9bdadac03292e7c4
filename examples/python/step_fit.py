#!/usr/bin/env python3
"""A first-order-plus-dead-time fit of a liquefier step log, with the 95 % interval of every
parameter, from Python.

    python3 examples/python/step_fit.py [LOG.csv]     (default: datasets/liquefier/synthetic_steps.csv)

The options are those of `tunekit step` (docs/python.md): the same fit, the same numbers.
"""

import os
import sys

import tunekit

here = os.path.dirname(os.path.abspath(__file__))
log = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "..", "datasets", "liquefier", "synthetic_steps.csv")

# The feed of this data set changes exactly at sample instants: --step-at first.
result = tunekit.step(log, time="time", input="feed", output="force", step_at="first")

print(f"pooled fit of {len(result['steps'])} steps ({result.fit.model}):")
for name, p in result.params.items():
    print(f"  {name:8s} = {p.value:.5g} {p.unit}   95 % [{p.ci95[0]:.5g}, {p.ci95[1]:.5g}]   stderr {p.stderr:.2g}")
tau = result.params["tau_s"]
print(f"tau_s = {tau.value:.3f} s, 95 % interval {tau.ci95[0]:.3f}..{tau.ci95[1]:.3f} s")
