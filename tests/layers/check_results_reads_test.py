#!/usr/bin/env python3
"""The results-reads check itself (scripts/check-results-reads): it passes on a copy of the clean
tree and fails, naming file and line, on the same copy with a JSON read of analysis results
planted outside the boundary readers; writes, comments and reads inside a boundary reader pass.

    python3 tests/layers/check_results_reads_test.py [--source DIR] [--work DIR]

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
    """Appends `text` (one or more lines) to tree/rel, creating it if needed; returns the line
    number of its first line."""
    path = os.path.join(tree, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    lines = 0
    if os.path.exists(path):
        with open(path, encoding="utf-8", errors="replace") as f:
            lines = sum(1 for _ in f)
    with open(path, "a", encoding="utf-8") as f:
        f.write(text + "\n")
    return lines + 1


def find(tree, name):
    """The path (relative to tree) of the source file called `name`."""
    for folder, _, names in os.walk(tree):
        if name in names:
            return os.path.relpath(os.path.join(folder, name), tree)
    raise SystemExit(f"no file {name} in the copy")


def run(check, tree):
    r = subprocess.run([sys.executable, check, "--root", tree], capture_output=True, text=True)
    return r.returncode, r.stdout + r.stderr


# (what, file name, planted line, a word the error names)
PLANTED = [
    ("a summary value looked up by its path", "calibrate_terminal.cpp",
     'const auto* v = json_at(results, "axes.x.modes[0].freq_hz");', "json_at()"),
    ("results.json parsed back in the report", "report.cpp",
     'const auto env = nlohmann::json::parse(read_file_bytes(run_dir + "/results.json"));', "parse"),
    ("plotdata.json read back by the command line", "report_cli.cpp",
     'const auto pd = tunekit::calibration::read_json_file(dir + "/plotdata.json");', "read_json_file()"),
    ("an analysis file read back in calibrate", "calibrate_results.cpp",
     'const nlohmann::json step = read_results_json(plan.run_dir + "/analysis/step.json");', "read_results_json()"),
    ("the ring's results read back from an outcome", "calibrate_results.cpp",
     'const double theta = cam.results.at("ring").at("theta_from_phase_s").get<double>();', '.results.at("'),
    ("summary rows read from a results variable", "calibrate_terminal.cpp",
     'for (const auto& row : results["summary"]) lines.push_back(row);', 'results["'),
    ("a value read from an envelope", "calibrate_run.cpp",
     'const std::string machine = envelope.value("machine", std::string());', 'envelope.value("'),
]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--source", default=os.path.normpath(os.path.join(HERE, "..", "..")))
    parser.add_argument("--work", default=None, help="folder for the copies (default: a temporary one)")
    args = parser.parse_args()
    check = os.path.join(args.source, "scripts", "check-results-reads")
    work = args.work or tempfile.mkdtemp(prefix="tunekit-check-results-reads-")
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

    # 2. Each planted read fails with FILE:LINE in the message, and only it is reported.
    for i, (what, name, line, expected) in enumerate(PLANTED):
        tree = fresh(f"planted{i}")
        rel = find(tree, name)
        number = plant(tree, rel, line)
        code, out = run(check, tree)
        where = f"{rel}:{number}:"
        if code != 1 or where not in out or expected not in out:
            failures.append(f"{what}: expected exit 1 and a line naming {where} and {expected}; got {code}:\n{out}")
        elif len([l for l in out.splitlines() if ": error: " in l]) != 1:
            failures.append(f"{what}: expected exactly one error, got:\n{out}")

    # 3. Not reads: writes into results JSON, comments, strings, declarations, and a read inside a
    #    boundary reader.
    tree = fresh("allowed")
    plant(tree, find(tree, "calibrate_results.cpp"), "\n".join([
        'void planted(nlohmann::json& res, Envelope& env) {',
        '  res["summary"] = nlohmann::json::array();',
        '  env.results()["machine"]["name"] = "sim";',
        '  res["figure_of_merit"] =',
        '      "a sentence";',
        '  // json_at(results, "a.b") and results["summary"] in a comment',
        '  const std::string s = "read_json_file(results.json)";',
        '}',
        '/* a block comment: json_at(results, "x")',
        '   results.at("summary") */',
        'nlohmann::json read_json_file(const std::string& path, std::string* bytes);',
    ]))
    plant(tree, find(tree, "calibration_record.cpp"),
          'double planted(const nlohmann::json& results) { return json_at(results, "a.b")->get<double>(); }')
    code, out = run(check, tree)
    if code != 0:
        failures.append(f"writes, comments and a boundary reader's read: expected exit 0, got {code}:\n{out}")

    # 4. A boundary reader that no longer reads is a stale entry: the list must stay honest.
    tree = fresh("stale")
    with open(os.path.join(tree, find(tree, "nozzle_command.cpp")), "w", encoding="utf-8") as f:
        f.write("// no reads here\n")
    code, out = run(check, tree)
    if code != 1 or "nozzle_command.cpp" not in out:
        failures.append(f"stale boundary reader: expected exit 1 naming nozzle_command.cpp, got {code}:\n{out}")

    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    if failures:
        print("\n\n".join(failures))
        return 1
    print(f"check-results-reads self-test: clean tree passes, {len(PLANTED)} planted reads fail with file and line")
    return 0


if __name__ == "__main__":
    sys.exit(main())
