"""tunekit from Python: the analyses of the `tunekit` command as functions, export and history.

Each analysis takes what the command takes: its files (paths), or tables in memory (a dict of
column name -> 1-D array, a pandas DataFrame), and keyword options named as the command's long
options with underscores (``step_at="first"`` is ``--step-at first``; a flag is ``True``). The
options are parsed by the command line's own binding and the work is the same library function,
so ``result.to_dict()`` equals the ``results`` of ``tunekit COMMAND --json``, number for number.

    >>> import tunekit
    >>> r = tunekit.step("synthetic_steps.csv", time="time", input="feed", output="force", step_at="first")
    >>> r.params["tau_s"].value, r.params["tau_s"].ci95

Bad input raises ValueError, a fit that failed tunekit.FitError (a RuntimeError), with the line
the command prints after "tunekit: error: ". The fits run without the GIL: independent analyses
may run in threads. docs/python.md describes the module.
"""

import json as _json
import math as _math
import os as _os
import tempfile as _tempfile

from . import _tunekit
from ._tunekit import FitError, MachineError  # noqa: F401 (the package's exceptions)

__version__ = _tunekit.__version__

__all__ = ["FitError", "MachineError", "Param", "Fit", "Result", "ExportResult", "step", "freq", "rheo", "nozzle",
           "resonance", "shaper", "belts", "linewidth", "overshoot", "delta", "thermal", "export", "history_list",
           "history_show", "history_trend", "history_records"]


class Param:
    """One fitted parameter: value, standard error, 95 % interval (lo, hi) and unit (NaN: not computed)."""

    def __init__(self, name, d):
        self.name = name
        self.value = _number(d.get("value"))
        self.stderr = _number(d.get("stderr"))
        ci = d.get("ci95") or [None, None]
        self.ci95 = (_number(ci[0]), _number(ci[1]))
        self.unit = d.get("unit", "")

    def __repr__(self):
        return f"Param({self.name}={self.value:g} {self.unit}, 95 % [{self.ci95[0]:g}, {self.ci95[1]:g}])"


class Fit:
    """A fitted model of a result: its parameters by name, diagnostics and, where the estimator
    computed one, the covariance of the estimate (numpy, in the order of ``covariance_names``, in
    the coordinates the solver used: ln of a parameter estimated as a logarithm)."""

    def __init__(self, d, covariance=None):
        self.model = d.get("model", "")
        self.params = {name: Param(name, p) for name, p in d["params"].items()}
        self.diagnostics = d.get("diagnostics", {})
        self.covariance_names, self.covariance = covariance if covariance is not None else (None, None)
        self._dict = d

    def __getitem__(self, name):
        return self.params[name]

    def to_dict(self):
        return _json.loads(_json.dumps(self._dict))


class Result:
    """What an analysis found. ``to_dict()`` is the command's JSON ``results``; ``fits`` every
    fitted model in them by JSON pointer ("" the results themselves, "/pooled", "/steps/0",
    "/fit", ...); ``params`` and ``covariance`` those of the main fit (the first of "", "/fit",
    "/pooled" that is one), ``warnings`` what the command warns about."""

    def __init__(self, command, text, covariances, outcome):
        envelope = _json.loads(text)
        self.command = command
        self.warnings = envelope.get("warnings", [])
        self._results = envelope["results"]
        self._outcome = outcome
        self.fits = {ptr: Fit(d, covariances.get(ptr)) for ptr, d in _fits_in(self._results, "")}
        main = next((self.fits[p] for p in ("", "/fit", "/pooled") if p in self.fits), None)
        self.fit = main
        self.params = main.params if main else {}
        self.covariance = main.covariance if main else None

    def __getitem__(self, key):
        return self._results[key]

    def to_dict(self):
        return _json.loads(_json.dumps(self._results))

    def __repr__(self):
        shown = ", ".join(f"{n}={p.value:g}" for n, p in self.params.items())
        return f"<tunekit {self.command} result{': ' + shown if shown else ''}>"


class ExportResult:
    """What export designed: ``to_dict()`` its JSON results (the settings, the diff), ``text``
    what the command prints (the configuration diff and the summary), ``exit_code``."""

    def __init__(self, text, printed, exit_code):
        self._results = _json.loads(text)["results"]
        self.text = printed
        self.exit_code = exit_code

    def __getitem__(self, key):
        return self._results[key]

    def to_dict(self):
        return _json.loads(_json.dumps(self._results))


def _number(v):
    return _math.nan if v is None else float(v)


def _fits_in(node, pointer):
    """(JSON pointer, object) of every fitted model in the results: objects with named params.
    Only objects and arrays are walked into: a number or a string holds no model, and a plot's
    arrays hold thousands of them."""
    if isinstance(node, dict):
        params = node.get("params")
        if isinstance(params, dict) and params and all(isinstance(p, dict) and "value" in p for p in params.values()):
            yield pointer, node
        for key, value in node.items():
            if isinstance(value, (dict, list)):
                yield from _fits_in(value, pointer + "/" + str(key).replace("~", "~0").replace("/", "~1"))
    elif isinstance(node, list):
        for i, value in enumerate(node):
            if isinstance(value, (dict, list)):
                yield from _fits_in(value, f"{pointer}/{i}")


def _keywords(options):
    """Keyword options as (name, [values as text]); [] is a flag given, False and None leave it out."""
    out = []
    for name, value in options.items():
        if value is None or value is False:
            continue
        if value is True:
            out.append((name, []))
        elif isinstance(value, (list, tuple)):
            out.append((name, [_text(v) for v in value]))
        else:
            out.append((name, [_text(value)]))
    return out


def _text(v):
    return repr(float(v)) if isinstance(v, float) else _os.fspath(v) if isinstance(v, _os.PathLike) else str(v)


def _csv_text(table):
    """A table (dict of column -> 1-D array, or a pandas DataFrame) as the CSV text tunekit reads,
    every number written so that it reads back exactly."""
    columns = list(table.keys())
    data = [list(map(float, table[c])) for c in columns]
    lengths = {len(d) for d in data}
    if len(lengths) != 1:
        raise ValueError("the table's columns have different lengths: " + ", ".join(
            f"{c}: {len(d)}" for c, d in zip(columns, data)))
    lines = [",".join(str(c) for c in columns)]
    lines += [",".join(repr(v) for v in row) for row in zip(*data)]
    return "\n".join(lines) + "\n"


def _is_table(x):
    return hasattr(x, "keys") and not isinstance(x, (str, bytes))


def _analysis(command, doc):
    native = getattr(_tunekit, command)

    def run(*inputs, **options):
        keywords = _keywords(options)
        if not any(_is_table(x) for x in inputs):
            return Result(command, *native([_text(x) for x in inputs], keywords))
        if command == "step" and len(inputs) == 1:  # read from memory by formats/csv
            return Result(command, *_tunekit.step_csv(["<table>"], keywords, "<table>", _csv_text(inputs[0])))
        with _tempfile.TemporaryDirectory(prefix="tunekit-") as folder:
            paths = []
            for i, x in enumerate(inputs):
                if _is_table(x):
                    path = _os.path.join(folder, f"table_{i}.csv")
                    with open(path, "w", encoding="utf-8") as f:
                        f.write(_csv_text(x))
                    x = path
                paths.append(_text(x))
            return Result(command, *native(paths, keywords))

    run.__name__ = command
    run.__doc__ = doc + "\n\nKeyword options: those of `tunekit " + command + " --help`, with underscores."
    return run


step = _analysis("step", "Liquefier dynamics (K, tau_s, theta_s) from a step-response log: step(file, output=..., ...)")
freq = _analysis("freq", "Liquefier frequency response from a sine-dwell or chirp log: freq(file, output=..., ...)")
rheo = _analysis("rheo", "Melt viscosity model fits from a rheometer table: rheo(file, model=..., ...)")
nozzle = _analysis("nozzle", "Nozzle pressure drop, or its inverse fit (fit=FILE): nozzle(K=..., n=..., flow=...)")
resonance = _analysis("resonance", "Axis modes (frequency, damping) from accelerometer files: resonance(*files)")
shaper = _analysis("shaper", "Input shaper design from accelerometer files (Klipper raw_data_*.csv, ...)")
belts = _analysis("belts", "Two belts compared from a pluck recording of each: belts(file_a, file_b)")
linewidth = _analysis("linewidth", "Line-width profiles from photos of printed lines: linewidth(*images, ...)")
overshoot = _analysis("overshoot", "Axis overshoot and settling at corners: overshoot(run_or_csv, ...)")
delta = _analysis("delta", "Delta printer geometry from probe heights: delta(file, ...)")
thermal = _analysis("thermal", "The hot end's thermal model from a thermal record or a klippy.log: thermal(file, ...)")


def export(*results, origins=None, **options):
    """Designs pressure advance and input shapers from result objects of step, freq and shaper,
    or from results files (paths) the command wrote, and previews the configuration change, or
    with ``write=True`` applies it: the command's own path, every file written together or none.
    ``origins`` names the result objects in messages (default "step result", ...).
    Keyword options: those of `tunekit export --help`, with underscores."""
    objects = [r for r in results if isinstance(r, Result)]
    files = [_text(r) for r in results if not isinstance(r, Result)]
    names = list(origins) if origins is not None else [f"{r.command} result" for r in objects]
    return ExportResult(*_tunekit.export([r._outcome for r in objects], names, files, _keywords(options)))


def _history_db(db):
    return _os.fspath(db) if db is not None else ""


def history_list(db=None, machines=()):
    """The calibration history: the machines (none named) or the records of the machines named,
    as the results of `tunekit history list --json` (dict of lists)."""
    return _json.loads(_tunekit.history_list(_history_db(db), list(machines)))["results"]


def history_show(record_id, db=None):
    """One record with its inputs, quantities and stored result (`tunekit history show ID`)."""
    return _json.loads(_tunekit.history_show(_history_db(db), int(record_id)))["results"]


def history_trend(db=None, machines=(), quantities=()):
    """Each machine's quantities against its baseline and their drift (`tunekit history trend`)."""
    return _json.loads(_tunekit.history_trend(_history_db(db), list(machines), list(quantities)))["results"]


def history_records(machine, db=None):
    """The records of one machine as a list of dicts, or a pandas DataFrame where pandas imports."""
    rows = history_list(db, [machine])
    records = _records_of(rows, machine)
    try:
        import pandas
    except ImportError:
        return records
    return pandas.DataFrame.from_records(records)


def _records_of(results, machine):
    return results.get("records", {}).get(machine, [])
