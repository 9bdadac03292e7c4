#!/usr/bin/env python3
"""An input shaper from a Klipper raw accelerometer file (raw_data_x_*.csv, as Klipper's
TEST_RESONANCES AXIS=X OUTPUT=raw_data writes it), chosen exactly as Klipper's calibrate_shaper.py
chooses (klipper_compatible), with the axis' identified mode beside it.

    python3 examples/python/shaper_klipper.py RAW_DATA.csv [MORE.csv ...]
"""

import sys

import tunekit

if len(sys.argv) < 2:
    sys.exit(__doc__)
result = tunekit.shaper(*sys.argv[1:], klipper_compatible=True)
for axis, found in result["axes"].items():
    rec = found["recommended"]
    print(f"axis {axis}: {rec['type']} at {rec['freq_hz']:.1f} Hz, remaining vibrations {rec['vibrations_pct']:.1f} %, "
          f"smoothing {rec['smoothing']:.3f}, max accel {rec['suggested_max_accel_mm_s2']:.0f} mm/s^2")
    for mode in found["modes"]:
        lo, hi = mode["freq_ci95"]
        print(f"  mode {mode['freq_hz']:.2f} Hz (95 % {lo:.2f}..{hi:.2f}), damping ratio {mode['zeta']:.3f} "
              f"(95 % {mode['zeta_ci95'][0]:.3f}..{mode['zeta_ci95'][1]:.3f})")
