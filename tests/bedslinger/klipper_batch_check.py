#!/usr/bin/env python3
"""Real Klipper's batch mode reads a G-code file scheduled by tunekit resonance --load-kg.

The local oracle for the per-layer SET_INPUT_SHAPER schedule: two simulated sweeps of the bed
axis (empty and with 0.6 kg), a small sliced print (PrusaSlicer-style layer marks, a line of
0.45 x 0.2 mm per move) post-processed with a fine step so that it changes the Y frequency on
several layers, then Klipper's klippy.py in batch mode (-i FILE -o OUT -d DICT, no printer
attached) with a config that has an [input_shaper] section. Klipper stops a batch run at the
first command it refuses ("error_exit"), so exit 0 and the frequencies in its input_shaper
status show that it accepted every inserted command.

    klipper_batch_check.py --tunekit build/apps/tunekit --work DIR

Klipper's checkout: $TUNEKIT_KLIPPER_DIR (a Klipper source tree, klippy/klippy.py) with a Linux
MCU data dictionary ($TUNEKIT_KLIPPER_DICT, default out/klipper.dict in the checkout: build it
with "make" after selecting the Linux process MCU in "make menuconfig"), run by
$TUNEKIT_KLIPPER_PYTHON (default /usr/bin/python3, with Debian's python3-cffi, python3-greenlet,
python3-jinja2). Without a checkout the check says why and exits 77 (skipped).
"""

import argparse
import json
import os
import re
import subprocess
import sys

PRINTER_CFG = """# tunekit's oracle printer: a bed slinger on Klipper's Linux process MCU
[mcu]
serial: /tmp/tunekit_oracle_mcu

[printer]
kinematics: cartesian
max_velocity: 300
max_accel: 3000
max_z_velocity: 5
max_z_accel: 100

[stepper_x]
step_pin: gpio1
dir_pin: gpio2
enable_pin: !gpio3
microsteps: 16
rotation_distance: 40
endstop_pin: ^gpio4
position_endstop: 0
position_max: 220
homing_speed: 50

[stepper_y]
step_pin: gpio5
dir_pin: gpio6
enable_pin: !gpio7
microsteps: 16
rotation_distance: 40
endstop_pin: ^gpio8
position_endstop: 0
position_max: 220
homing_speed: 50

[stepper_z]
step_pin: gpio9
dir_pin: gpio10
enable_pin: !gpio11
microsteps: 16
rotation_distance: 8
endstop_pin: ^gpio12
position_endstop: 0.5
position_max: 200

[extruder]
step_pin: gpio13
dir_pin: gpio14
enable_pin: !gpio15
microsteps: 16
rotation_distance: 33.5
nozzle_diameter: 0.400
filament_diameter: 1.750
heater_pin: gpio16
sensor_type: EPCOS 100K B57560G104F
sensor_pin: analog0
control: pid
pid_Kp: 22.2
pid_Ki: 1.08
pid_Kd: 114
min_temp: 0
max_temp: 260
min_extrude_temp: 0

[input_shaper]
shaper_type_x: mzv
shaper_freq_x: 48
shaper_type_y: mzv
shaper_freq_y: {freq_y}
"""


def sliced_print(layers):
    """A square of 100 mm per layer, 0.45 x 0.2 mm lines (0.0374 mm of filament per mm)."""
    e_per_mm = 0.45 * 0.2 / (3.141592653589793 / 4 * 1.75 ** 2)
    out = ["; a test print", "M83", "G28", "G1 Z5 F600"]
    for layer in range(layers):
        z = 0.2 * (layer + 1)
        out += [";LAYER_CHANGE", f";Z:{z:.1f}", f"G1 Z{z:.1f} F600", "G1 X60 Y60 F9000"]
        for x, y in ((160, 60), (160, 160), (60, 160), (60, 60)):
            out.append(f"G1 X{x} Y{y} E{100 * e_per_mm:.5f} F3000")
        out += ["G1 E-0.8 F2400", "G1 E0.8 F2400"]
    out.append("M84")
    return "\n".join(out) + "\n"


def run(cmd, **kw):
    return subprocess.run(cmd, capture_output=True, text=True, **kw)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tunekit", required=True)
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    klipper = os.environ.get("TUNEKIT_KLIPPER_DIR", "")
    if not klipper:
        print("skipped: no Klipper checkout (set TUNEKIT_KLIPPER_DIR to a Klipper source tree)")
        return 77
    dictionary = os.environ.get("TUNEKIT_KLIPPER_DICT", os.path.join(klipper, "out", "klipper.dict"))
    python = os.environ.get("TUNEKIT_KLIPPER_PYTHON", "/usr/bin/python3")
    for path in (os.path.join(klipper, "klippy", "klippy.py"), dictionary):
        if not os.path.isfile(path):
            print(f"skipped: {path} is missing (build Klipper's Linux process MCU: make menuconfig, make)")
            return 77
    os.makedirs(a.work, exist_ok=True)

    accel = []
    for load in ("0", "0.6"):
        r = run([a.tunekit, "run", "axis-sweep", "--axis", "y", "--machine", "sim", "-p", f"load_kg={load}",
                 "--run-dir", os.path.join(a.work, f"sweep_{load}"), "--json"])
        if r.returncode != 0:
            print(r.stderr)
            return 1
        accel.append(json.loads(r.stdout)["results"]["files"]["accel"])
    gcode_in = os.path.join(a.work, "print.gcode")
    gcode_out = os.path.join(a.work, "print.scheduled.gcode")
    with open(gcode_in, "w") as f:
        f.write(sliced_print(40))
    r = run([a.tunekit, "resonance", *accel, "--axis", "y", "--load-kg", "0", "--load-kg", "0.6", "--gcode-in",
             gcode_in, "--gcode-out", gcode_out, "--step-hz", "0.005", "--json"])
    if r.returncode != 0:
        print(r.stderr)
        return 1
    res = json.loads(r.stdout)["results"]["bed_mass"]
    changes = res["gcode_post"]["changes"]
    if len(changes) < 3:
        print(f"the schedule changed the frequency on {len(changes)} layers only")
        return 1
    base = res["schedule"]["base_hz"] if "schedule" in res else None
    with open(os.path.join(a.work, "printer.cfg"), "w") as f:
        f.write(PRINTER_CFG.format(freq_y=f"{base:.2f}" if base else "42"))
    log = os.path.join(a.work, "klippy.log")
    r = run([python, os.path.join(klipper, "klippy", "klippy.py"), os.path.join(a.work, "printer.cfg"), "-i",
             gcode_out, "-o", os.path.join(a.work, "klippy.serial"), "-d", dictionary, "-l", log], timeout=600)
    with open(log) as f:
        text = f.read()
    refused = [l for l in text.splitlines() if "Unknown command" in l or l.startswith("!! ")]
    if r.returncode != 0 or refused:
        print(f"Klipper's batch mode refused the file (exit {r.returncode}):")
        print("\n".join(refused[:10]) or text[-2000:])
        return 1
    # SET_INPUT_SHAPER answers with the settings in force: one Y line per inserted command, the
    # last at the schedule's last frequency.
    seen = [float(v) for v in re.findall(r"shaper_freq_y:([0-9.]+)", text)]
    if len(seen) != len(changes) or abs(seen[-1] - changes[-1]["freq_hz"]) > 0.001:
        print(f"Klipper reported Y frequencies {seen}, the schedule wrote {[c['freq_hz'] for c in changes]}")
        return 1
    print(f"Klipper's batch mode ran {gcode_out}: {len(changes)} SET_INPUT_SHAPER SHAPER_FREQ_Y= lines "
          f"({changes[0]['freq_hz']:.2f} -> {changes[-1]['freq_hz']:.2f} Hz), exit 0")
    return 0


if __name__ == "__main__":
    sys.exit(main())
