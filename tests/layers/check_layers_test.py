#!/usr/bin/env python3
"""The layering check itself (scripts/check-layers): it passes on a copy of the clean tree
and fails, naming file and line, on the same copy with an upward include planted in it: in
every room of the table, and in the cases named below; and it fails when one room of the
library grows past its share.

    python3 tests/layers/check_layers_test.py [--source DIR] [--work DIR]

Exit 0 when every case behaves, 1 with the failing case's output otherwise.
"""

import argparse
import importlib.machinery
import importlib.util
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SUFFIXES = (".hpp", ".h", ".cpp")


def load_check(path):
    """scripts/check-layers as a module, for its table of rooms."""
    loader = importlib.machinery.SourceFileLoader("check_layers", path)
    spec = importlib.util.spec_from_loader("check_layers", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def copy_sources(source, dest, rooms):
    """Copies the rooms' sources (not datasets or build folders) into dest."""
    for library in sorted({room.split("/")[0] for room in rooms}):
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


def room_source(tree, room):
    """The first .cpp of a room (apps keeps its sources in cli/src)."""
    return first_source(tree, "apps/cli/src" if room == "apps" else f"{room}/src")


def upward_cases(layers, prefix_of):
    """For every room with a room it may not include: a planted include of that room's header."""
    cases = []
    for room, allowed in layers.items():
        forbidden = [other for other in layers if other not in allowed]
        if not forbidden:
            continue
        # The nearest forbidden room in the table's order above this one, else the first beside it.
        order = list(layers)
        above = [o for o in forbidden if order.index(o) > order.index(room)]
        other = above[0] if above else forbidden[0]
        header = f"tunekit/{prefix_of(other)}/planted.hpp"
        cases.append((f"{room} includes {other}", lambda t, r=room: room_source(t, r), f'#include "{header}"', header))
    return cases


def run(check, tree):
    r = subprocess.run([sys.executable, check, "--root", tree], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--source", default=os.path.normpath(os.path.join(HERE, "..", "..")))
    parser.add_argument("--work", default=None, help="folder for the copies (default: a temporary one)")
    args = parser.parse_args()
    check = os.path.join(args.source, "scripts", "check-layers")
    layers = load_check(check)
    rooms = layers.LAYERS
    work = args.work or tempfile.mkdtemp(prefix="tunekit-check-layers-")
    failures = []

    def fresh(name):
        tree = os.path.join(work, name)
        shutil.rmtree(tree, ignore_errors=True)
        copy_sources(args.source, tree, rooms)
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
         "#include <tunekit/ident/spectrum.hpp>", "tunekit/ident/spectrum.hpp"),
        ("fitting includes protocols", lambda t: first_source(t, "fitting/src"),
         '#include "tunekit/machine/machine_profile.hpp"', "tunekit/machine/machine_profile.hpp"),
        ("fitting includes formats with <>", lambda t: first_source(t, "fitting/src"),
         "#include <tunekit/formats/csv.hpp>", "tunekit/formats/csv.hpp"),
        ("ident includes design (above it)", lambda t: first_source(t, "ident/src"),
         '#include "tunekit/design/input_shaper.hpp"', "tunekit/design/input_shaper.hpp"),
        ("machine includes ident", lambda t: first_source(t, "machine/src"),
         '#include "tunekit/ident/spectrum.hpp"', "tunekit/ident/spectrum.hpp"),
        ("protocols includes sim (the simulator is injected from above)", lambda t: first_source(t, "protocols/src"),
         '#include "tunekit/sim/simulator.hpp"', "tunekit/sim/simulator.hpp"),
        ("calibration's results include its presentation", lambda t: first_source(t, "calibration/results/src"),
         '#include "tunekit/calibration/presentation/plots.hpp"', "tunekit/calibration/presentation/plots.hpp"),
        ("ident includes protocols in a public header", lambda t: "ident/include/tunekit/ident/spectrum.hpp",
         '#  include "tunekit/machine/gcode.hpp"', "tunekit/machine/gcode.hpp"),
        ("ident includes vision (beside it)", lambda t: first_source(t, "ident/src"),
         '#include "tunekit/vision/line_width.hpp"', "tunekit/vision/line_width.hpp"),
        ("vision includes ident (beside it)", lambda t: "vision/src/planted.cpp",
         '#include "tunekit/ident/spectrum.hpp"', "tunekit/ident/spectrum.hpp"),
        ("history includes protocols", lambda t: first_source(t, "history/src"),
         '#include "tunekit/machine/journal.hpp"', "tunekit/machine/journal.hpp"),
        ("firmware includes machine", lambda t: first_source(t, "firmware/src"),
         '#include "tunekit/machine/transport.hpp"', "tunekit/machine/transport.hpp"),
        ("firmware includes protocols in a public header",
         lambda t: "firmware/include/tunekit/firmware/firmware_export.hpp",
         '#include "tunekit/protocols/safety.hpp"', "tunekit/protocols/safety.hpp"),
        ("machine includes sim", lambda t: first_source(t, "machine/src"),
         '#include "tunekit/sim/simulator.hpp"', "tunekit/sim/simulator.hpp"),
        ("machine includes protocols", lambda t: first_source(t, "machine/src"),
         '#include "tunekit/protocols/runner.hpp"', "tunekit/protocols/runner.hpp"),
        ("sim includes protocols", lambda t: first_source(t, "sim/src"),
         '#include "tunekit/protocols/experiments.hpp"', "tunekit/protocols/experiments.hpp"),
        ("core includes firmware", lambda t: "core/src/atomic_file.cpp",
         '#include "tunekit/firmware/config_edit.hpp"', "tunekit/firmware/config_edit.hpp"),
        ("protocols includes calibration", lambda t: first_source(t, "protocols/src"),
         '#include "tunekit/calibration/analyses/step_command.hpp"', "tunekit/calibration/analyses/step_command.hpp"),
        ("history includes calibration", lambda t: first_source(t, "history/src"),
         '#include "tunekit/calibration/results/envelope.hpp"', "tunekit/calibration/results/envelope.hpp"),
        ("calibration includes the command line", lambda t: first_source(t, "calibration/guided/src"),
         '#include "tunekit/cli/option_binding.hpp"', "tunekit/cli/option_binding.hpp"),
        ("calibration includes apps' private header by a relative path",
         lambda t: first_source(t, "calibration/guided/src"), '#include "../../../apps/cli/src/resonance_cli.hpp"',
         "apps"),
        ("calibration's analyses reach into its commands' folder by a relative path",
         lambda t: first_source(t, "calibration/analyses/src"), '#include "../../commands/src/history_common.hpp"',
         "calibration/commands"),
        ("fitting reaches into ident's folder by a relative path", lambda t: first_source(t, "fitting/src"),
         '#include "../../ident/src/planted_private.hpp"', "ident"),
    ]
    cases += upward_cases(rooms, layers.include_prefix)
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

    # 3. Allowed includes stay allowed: protocols may include vision, apps may include history,
    #    the Python module the command line's headers, every library may include core.
    tree = fresh("allowed")
    for library in ("fitting", "ident", "vision", "history", "firmware", "machine", "sim", "protocols"):
        plant(tree, first_source(tree, f"{library}/src"), '#include "tunekit/core/error.hpp"')
    plant(tree, first_source(tree, "protocols/src"), '#include "tunekit/vision/line_width.hpp"')
    plant(tree, first_source(tree, "sim/src"), '#include "tunekit/machine/transport.hpp"')
    plant(tree, first_source(tree, "sim/src"), '#include "tunekit/design/shaper_defs.hpp"')
    plant(tree, first_source(tree, "ident/src"), '#include "tunekit/formats/csv.hpp"')
    plant(tree, first_source(tree, "machine/src"), '#include "tunekit/firmware/firmware_limits.hpp"')
    plant(tree, "apps/tunekit_main.cpp", '#include "tunekit/history/store.hpp"')
    plant(tree, "apps/tunekit_main.cpp", '#include "tunekit/calibration/analyses/step_command.hpp"')
    plant(tree, first_source(tree, "python/src"), '#include "tunekit/cli/analysis_commands.hpp"')
    plant(tree, first_source(tree, "python/src"), '#include "tunekit/calibration/commands/export_command.hpp"')
    plant(tree, first_source(tree, "calibration/guided/src"), '#include "tunekit/protocols/runner.hpp"')
    plant(tree, first_source(tree, "calibration/guided/src"), '#include "tunekit/sim/simulator.hpp"')
    plant(tree, first_source(tree, "calibration/results/src"), '#include "tunekit/history/store.hpp"')
    plant(tree, first_source(tree, "calibration/analyses/src"), '#include "tunekit/calibration/results/envelope.hpp"')
    code, out = run(check, tree)
    if code != 0:
        failures.append(f"allowed includes: expected exit 0, got {code}:\n{out}")

    # 4. A source file in calibration/ outside its rooms fails, naming the file.
    tree = fresh("homeless")
    plant(tree, "calibration/src/planted_homeless.cpp", "int planted_homeless = 0;")
    code, out = run(check, tree)
    if code != 1 or "calibration/src/planted_homeless.cpp: error: in no room" not in out:
        failures.append(f"a file outside the rooms: expected exit 1 naming it, got {code}:\n{out}")

    # 5. A room of the library that grows past its share fails, naming the room.
    tree = fresh("oversized")
    filler = "\n".join(f"int planted_{i} = {i};" for i in range(12000)) + "\n"
    with open(os.path.join(tree, "history", "src", "planted_filler.cpp"), "w", encoding="utf-8") as f:
        f.write(filler)
    code, out = run(check, tree)
    if code != 1 or "history/: error: history holds" not in out:
        failures.append(f"an oversized room: expected exit 1 naming history/, got {code}:\n{out}")

    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    if failures:
        print("\n\n".join(failures))
        return 1
    print(f"check-layers self-test: clean tree passes, {len(cases)} planted includes (one upward into each room) "
          "fail with file and line, an oversized room fails")
    return 0


if __name__ == "__main__":
    sys.exit(main())
