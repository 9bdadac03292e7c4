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
    print(f"axis {axis}: {rec['type']} at {rec['freq_hz']:.1f} Hz, "
          f"remaining vibrations {100 * rec['vibrations']:.1f} %, smoothing {rec['smoothing']:.3f}, "
          f"max accel {rec['max_accel_mm_s2']:.0f} mm/s^2")
