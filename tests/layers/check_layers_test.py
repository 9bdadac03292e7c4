#!/usr/bin/env python3
"""The layering check itself (scripts/check-layers): it passes on a copy of the clean tree
and fails, naming file and line, on the same copy with an upward include planted in it.

    python3 tests/layers/check_layers_test.py [--source DIR] [--work DIR]

Exit 0 when every case behaves, 1 with the failing case's output otherwise.
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
LIBRARIES = ("core", "fitting", "ident", "vision", "history", "firmware", "machine", "sim", "protocols", "calibration",
             "apps")
SUFFIXES = (".hpp", ".h", ".cpp")


def copy_sources(source, dest):
    """Copies the libraries' sources (not datasets or build folders) into dest."""
    for library in LIBRARIES:
        top = os.path.join(source, library)
        if not os.path.isdir(top):
            continue
        for folder, _, names in os.walk(top):
            for name in names:
                if name.endswith(SUFFIXES):
                    rel = os.path.relpath(os.path.join(folder, name), source)
                    os.makedirs(os.path.join(dest, os.path.dirname(rel)), exist_ok=True)
                    shutil.copy2(os.path.join(source, rel), os.path.join(dest, rel))


def plant(tree, rel, text):
    """Appends `text` (one line) to tree/rel, creating it if needed; returns its line number."""
    path = os.path.join(tree, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    lines = 0
    if os.path.exists(path):
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = sum(1 for _ in f)
    with open(path, "a", encoding="utf-8") as f:
        f.write(text + "\n")
    return lines + 1


def first_source(tree, folder):
    for name in sorted(os.listdir(os.path.join(tree, folder))):
        if name.endswith(".cpp"):
            return os.path.join(folder, name)
    raise SystemExit(f"no .cpp file in {folder}")


def run(check, tree):
    r = subprocess.run([sys.executable, check, "--root", tree], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--source", default=os.path.normpath(os.path.join(HERE, "..", "..")))
    parser.add_argument("--work", default=None, help="folder for the copies (default: a temporary one)")
    args = parser.parse_args()
    check = os.path.join(args.source, "scripts", "check-layers")
    work = args.work or tempfile.mkdtemp(prefix="tunekit-check-layers-")
    failures = []

    def fresh(name):
        tree = os.path.join(work, name)
        shutil.rmtree(tree, ignore_errors=True)
        copy_sources(args.source, tree)
        return tree

    # 1. The clean tree passes.
    code, out = run(check, fresh("clean"))
    if code != 0:
        failures.append(f"clean tree: expected exit 0, got {code}:\n{out}")

    # 2. Planted upward or sideways includes fail with FILE:LINE in the message.
    cases = [
        ("core includes fitting", lambda t: first_source(t, "core/src"),
         '#include "tunekit/fitting/stats.hpp"', "tunekit/fitting/stats.hpp"),
        ("core includes ident in a public header", lambda t: "core/include/tunekit/core/error.hpp",
         "#include <tunekit/ident/csv.hpp>", "tunekit/ident/csv.hpp"),
        ("fitting includes protocols", lambda t: first_source(t, "fitting/src"),
         '#include "tunekit/machine/machine_profile.hpp"', "tunekit/machine/machine_profile.hpp"),
        ("fitting includes ident with <>", lambda t: first_source(t, "fitting/src"),
         "#include <tunekit/ident/csv.hpp>", "tunekit/ident/csv.hpp"),
        ("ident includes protocols in a public header", lambda t: "ident/include/tunekit/ident/csv.hpp",
         '#  include "tunekit/machine/gcode.hpp"', "tunekit/machine/gcode.hpp"),
        ("ident includes vision (beside it)", lambda t: first_source(t, "ident/src"),
         '#include "tunekit/vision/line_width.hpp"', "tunekit/vision/line_width.hpp"),
        ("vision includes ident (beside it)", lambda t: "vision/src/planted.cpp",
         '#include "tunekit/ident/csv.hpp"', "tunekit/ident/csv.hpp"),
        ("history includes protocols", lambda t: first_source(t, "history/src"),
         '#include "tunekit/machine/journal.hpp"', "tunekit/machine/journal.hpp"),
        ("firmware includes machine", lambda t: first_source(t, "firmware/src"),
         '#include "tunekit/machine/transport.hpp"', "tunekit/machine/transport.hpp"),
        ("firmware includes protocols in a public header",
         lambda t: "firmware/include/tunekit/firmware/firmware_export.hpp",
         '#include "tunekit/protocols/safety.hpp"', "tunekit/protocols/safety.hpp"),
        ("machine includes sim", lambda t: first_source(t, "machine/src"),
         '#include "tunekit/sim/simulator.hpp"', "tunekit/sim/simulator.hpp"),
        ("machine includes ident (firmware builds on it, machine does not)",
         lambda t: first_source(t, "machine/src"), '#include "tunekit/ident/csv.hpp"', "tunekit/ident/csv.hpp"),
        ("machine includes protocols", lambda t: first_source(t, "machine/src"),
         '#include "tunekit/protocols/runner.hpp"', "tunekit/protocols/runner.hpp"),
        ("protocols includes sim (beside it)", lambda t: first_source(t, "protocols/src"),
         '#include "tunekit/sim/simulator.hpp"', "tunekit/sim/simulator.hpp"),
        ("sim includes protocols", lambda t: first_source(t, "sim/src"),
         '#include "tunekit/protocols/experiments.hpp"', "tunekit/protocols/experiments.hpp"),
        ("core includes firmware", lambda t: "core/src/atomic_file.cpp",
         '#include "tunekit/firmware/config_edit.hpp"', "tunekit/firmware/config_edit.hpp"),
        ("protocols includes calibration", lambda t: first_source(t, "protocols/src"),
         '#include "tunekit/calibration/step_command.hpp"', "tunekit/calibration/step_command.hpp"),
        ("history includes calibration", lambda t: first_source(t, "history/src"),
         '#include "tunekit/calibration/envelope.hpp"', "tunekit/calibration/envelope.hpp"),
        ("calibration includes the command line", lambda t: first_source(t, "calibration/src"),
         '#include "tunekit/cli/option_binding.hpp"', "tunekit/cli/option_binding.hpp"),
        ("calibration includes apps' private header by a relative path", lambda t: first_source(t, "calibration/src"),
         '#include "../../apps/cli/src/resonance_cli.hpp"', "apps"),
        ("fitting reaches into ident's folder by a relative path", lambda t: first_source(t, "fitting/src"),
         '#include "../../ident/src/planted_private.hpp"', "ident"),
    ]
    for i, (what, target, line, expected) in enumerate(cases):
        tree = fresh(f"planted{i}")
        rel = target(tree)
        number = plant(tree, rel, line)
        code, out = run(check, tree)
        where = f"{rel}:{number}:"
        if code != 1 or where not in out or expected not in out:
            failures.append(f"{what}: expected exit 1 and a line naming {where} and {expected}; got {code}:\n{out}")
        # Only the planted line is reported.
        elif len([l for l in out.splitlines() if ": error: " in l]) != 1:
            failures.append(f"{what}: expected exactly one violation, got:\n{out}")

    # 3. Allowed includes stay allowed: protocols may include vision, calibration sim, apps
    #    history, every library may include core.
    tree = fresh("allowed")
    for library in ("fitting", "ident", "vision", "history", "firmware", "machine", "sim", "protocols"):
        plant(tree, first_source(tree, f"{library}/src"), '#include "tunekit/core/error.hpp"')
    plant(tree, first_source(tree, "protocols/src"), '#include "tunekit/vision/line_width.hpp"')
    plant(tree, first_source(tree, "calibration/src"), '#include "tunekit/sim/simulator.hpp"')
    plant(tree, first_source(tree, "sim/src"), '#include "tunekit/machine/transport.hpp"')
    plant(tree, first_source(tree, "machine/src"), '#include "tunekit/firmware/firmware_limits.hpp"')
    plant(tree, "apps/tunekit_main.cpp", '#include "tunekit/history/store.hpp"')
    plant(tree, "apps/tunekit_main.cpp", '#include "tunekit/calibration/step_command.hpp"')
    plant(tree, first_source(tree, "calibration/src"), '#include "tunekit/protocols/runner.hpp"')
    plant(tree, first_source(tree, "calibration/src"), '#include "tunekit/history/store.hpp"')
    code, out = run(check, tree)
    if code != 0:
        failures.append(f"allowed includes: expected exit 0, got {code}:\n{out}")

    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    if failures:
        print("\n\n".join(failures))
        return 1
    print(f"check-layers self-test: clean tree passes, {len(cases)} planted includes fail with file and line")
    return 0


if __name__ == "__main__":
    sys.exit(main())
