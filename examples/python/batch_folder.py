#!/usr/bin/env python3
"""Every Klipper spectrum or raw accelerometer file of a folder, analysed in parallel threads
(the fits run without the GIL), one line each; a file that is not one is listed with the reason.

    python3 examples/python/batch_folder.py FOLDER [THREADS]
"""

import concurrent.futures
import os
import sys

import tunekit

if len(sys.argv) < 2:
    sys.exit(__doc__)
folder = sys.argv[1]
threads = int(sys.argv[2]) if len(sys.argv) > 2 else 2
files = sorted(os.path.join(folder, f) for f in os.listdir(folder) if f.endswith(".csv"))


def analyse(path):
    try:
        return path, tunekit.shaper(path, klipper_compatible=True), None
    except ValueError as e:  # not an accelerometer record: the command's one-line message
        return path, None, str(e)


with concurrent.futures.ThreadPoolExecutor(max_workers=threads) as pool:
    for path, result, error in pool.map(analyse, files):
        name = os.path.basename(path)
        if error:
            print(f"{name}: skipped: {error}")
            continue
        for axis, found in result["axes"].items():
            rec = found["recommended"]
            print(f"{name}: axis {axis}: {rec['type']} {rec['freq_hz']:.1f} Hz")
