#!/usr/bin/env python3
"""Writes a Klipper raw accelerometer file (raw_data_x_sim.csv in FOLDER) from the simulated
printer's X resonance sweep, for the shaper example.

    klipper_raw_file.py TUNEKIT FOLDER
"""

import json
import os
import shutil
import subprocess
import sys

tunekit, folder = sys.argv[1], sys.argv[2]
shutil.rmtree(folder, ignore_errors=True)
os.makedirs(folder)
r = subprocess.run([tunekit, "run", "axis-sweep", "--axis", "x", "--machine", "sim", "--run-dir",
                    os.path.join(folder, "run"), "--json"], capture_output=True, text=True)
if r.returncode != 0:
    sys.exit(f"tunekit run axis-sweep: exit {r.returncode}: {r.stderr}")
accel = json.loads(r.stdout)["results"]["files"]["accel"]
shutil.copy(accel, os.path.join(folder, "raw_data_x_sim.csv"))
print(os.path.join(folder, "raw_data_x_sim.csv"))
