"""Every analysis from Python gives the command's --json results, number for number, on the data
sets the command's own tests use; and the typed view of them (Param, covariance) reads the same."""

import math
import os
import shlex
import subprocess

import numpy as np
import pytest

import tunekit
from conftest import cli_results, dataset

# (analysis, positional inputs, keyword options): each case is also run as
# `tunekit ANALYSIS INPUTS --option value ...` and the two results compared.
CASES = [
    ("step", [dataset("liquefier/synthetic_steps.csv")],
     dict(time="time", input="feed", output="force", step_at="first")),
    ("step", [dataset("liquefier/holtrup_table_b1_ooze.csv")],
     dict(time="t_s", output="L_mm", group="v_print_mm_s", model="fo")),
    ("freq", [dataset("liquefier/appendix_d/exp_07.csv")],
     dict(time="time", output="width", input="setpoint_width", freq_hz=0.05305165)),
    ("freq", [dataset("liquefier/synthetic_chirp.csv")],
     dict(time="time", input="feed", output="force", mode="h1", fit_tf="2,0", fmax=40)),
    ("rheo", [dataset("rheology/peek_cross_wlf_synthetic.csv")], dict(model="cross-wlf")),
    ("rheo", [dataset("rheology/peek_cross_wlf_synthetic.csv")],
     dict(model="cross-wlf", power_law_window="600:950", power_law_at=405)),
    ("nozzle", [], dict(K=10114, n=0.51, flow=20, cone_angle=45)),
    ("nozzle", [], dict(fit=dataset("rheology/nozzle_pressure_synthetic.csv"))),
    ("resonance", [dataset("klipper_spectra/resonances_x_20220317_143228.csv")], {}),
    ("resonance", [dataset("belts/adxl345-belt_A_1_cut.csv")], dict(ringdown=True)),
    ("shaper", [dataset("klipper_spectra/resonances_x_20220317_143228.csv")], dict(klipper_compatible=True)),
    ("shaper", [dataset("klipper_sweeps/inputshaper_20250509_131744_axis_X.stdata")], dict(max_smoothing=0.2)),
    ("belts", [dataset("belts/adxl345-belt_A_1_cut.csv"), dataset("belts/adxl345-belt_B_1_cut.csv")], {}),
    ("delta", [dataset("delta/probes_simulated.csv")], dict(radius=105, rod=215, height=250, factors=6)),
    ("thermal", [dataset("thermal/klippy_cetus3d/klippy-heatup.log")], dict(until=300.0)),
]


def command_line(options):
    """The keyword options as the command line spells them."""
    args = []
    for name, value in options.items():
        flag = ("--" if len(name) > 1 or name in ("K", "n") else "-") + name.replace("_", "-")
        args += [flag] if value is True else [flag, repr(value) if isinstance(value, float) else str(value)]
    return args


@pytest.mark.parametrize("analysis,inputs,options", CASES,
                         ids=[f"{c[0]}-{i}" for i, c in enumerate(CASES)])
def test_results_equal_the_commands(analysis, inputs, options):
    result = getattr(tunekit, analysis)(*inputs, **options)
    expected = cli_results(analysis, *inputs, *command_line(options))
    assert result.to_dict() == expected


def test_linewidth_results_equal_the_commands(tmp_path):
    # A dark photo of two light printed lines, 20 px/mm: 0.45 and 0.6 mm wide (9 and 12 px).
    image = np.full((120, 400), 30, dtype=np.uint8)
    image[30:39, 20:380] = 220
    image[80:92, 20:380] = 220
    path = tmp_path / "lines.pgm"
    path.write_bytes(b"P5\n400 120\n255\n" + image.tobytes())
    result = tunekit.linewidth(path, px_per_mm=20)
    assert result.to_dict() == cli_results("linewidth", path, "--px-per-mm", "20")


def overshoot_record():
    """An encoder log of one 40 mm move between two rests: a trapezoid with a 35 Hz, 0.06 mode's
    ringing after it, 5 kHz, 1 um steps (columns t_s, x_mm)."""
    t = np.arange(0, 1.4, 2e-4)
    v, a, length, rest = 120.0, 4000.0, 40.0, 0.3
    ta, tc = v / a, (length - v * v / a) / v
    s = np.clip(t - rest, 0, None)
    x = np.where(s < ta, 0.5 * a * s * s, np.where(s < ta + tc, 0.5 * a * ta * ta + v * (s - ta),
                 length - 0.5 * a * np.clip(2 * ta + tc - s, 0, None) ** 2))
    w, zeta, end = 2 * np.pi * 35, 0.06, rest + 2 * ta + tc
    after = np.clip(t - end, 0, None)
    x = x + np.where(t > end, 0.05 * np.exp(-zeta * w * after) * np.sin(w * np.sqrt(1 - zeta ** 2) * after), 0)
    return {"t_s": t, "x_mm": np.round((10 + x) * 1000) / 1000}


def test_overshoot_results_equal_the_commands_and_a_table_in_memory_reads_as_the_file(tmp_path):
    table = overshoot_record()
    path = tmp_path / "encoder.csv"
    path.write_text(tunekit._csv_text(table))
    options = dict(time="t_s", position_x="x_mm", band_mm=0.01)
    expected = cli_results("overshoot", path, *command_line(options))
    assert tunekit.overshoot(path, **options).to_dict() == expected
    assert tunekit.overshoot(table, **options).to_dict() == expected


def test_step_from_numpy_arrays_reads_as_the_file():
    """Columns in memory go through the same CSV reader, from memory, and give the file's numbers."""
    path = dataset("liquefier/synthetic_steps.csv")
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    names = lines[0].strip().split(",")  # "time (s)", "feed (mm/s)", ...: units in the names, as in the file
    data = np.loadtxt(lines[1:], delimiter=",")
    table = {name: data[:, i] for i, name in enumerate(names)}
    options = dict(time="time", input="feed", output="force", step_at="first")
    from_memory = tunekit.step(table, **options).to_dict()
    assert from_memory == cli_results("step", path, *command_line(options))


def test_a_parameter_carries_value_stderr_interval_and_the_fit_its_covariance():
    r = tunekit.step(dataset("liquefier/synthetic_steps.csv"), time="time", input="feed", output="force",
                     step_at="first")
    pooled = r.to_dict()["pooled"]["params"]
    tau = r.params["tau_s"]
    assert tau.value == pooled["tau_s"]["value"]
    assert tau.stderr == pooled["tau_s"]["stderr"]
    assert tau.ci95 == tuple(pooled["tau_s"]["ci95"])
    assert tau.ci95[0] < tau.value < tau.ci95[1]
    cov = r.covariance
    assert isinstance(cov, np.ndarray) and cov.shape == (len(r.fit.covariance_names),) * 2
    assert np.allclose(cov, cov.T)
    # The covariance's diagonal is the variance the standard errors come from (tau is estimated as
    # itself here, or as its logarithm: then stderr = tau * sqrt(var(ln tau)) to first order).
    i = r.fit.covariance_names.index("tau_s")
    assert math.isclose(math.sqrt(cov[i, i]), tau.stderr, rel_tol=1e-6) or \
        math.isclose(tau.value * math.sqrt(cov[i, i]), tau.stderr, rel_tol=1e-6)
    # Every fitted model of the results is a Fit by its JSON pointer, the single steps' too.
    assert {"/pooled", "/steps/0", "/steps/3"} <= set(r.fits)
    assert r.fits["/steps/0"].params["tau_s"].value == r.to_dict()["steps"][0]["params"]["tau_s"]["value"]


def test_the_other_fits_with_a_covariance_carry_it():
    fits = [tunekit.freq(dataset("liquefier/synthetic_chirp.csv"), time="time", input="feed", output="force",
                         mode="h1", fit_tf="2,0", fmax=40).fit,
            tunekit.rheo(dataset("rheology/peek_cross_wlf_synthetic.csv"), model="cross-wlf").fit,
            tunekit.nozzle(fit=dataset("rheology/nozzle_pressure_synthetic.csv")).fit]
    for fit in fits:
        assert sorted(fit.covariance_names) == sorted(fit.params)  # in the estimator's order; params by name
        assert fit.covariance.shape == (len(fit.params), len(fit.params))
        assert np.all(np.diag(fit.covariance) >= 0) and np.any(np.diag(fit.covariance) > 0)


def test_the_version_is_the_commands_and_python3_finds_the_module_as_the_readme_says():
    from conftest import cli
    assert cli("--version")[1].strip() == f"tunekit {tunekit.__version__}"
    # README: export PYTHONPATH=$PWD/build/python && python3 -c "import tunekit; print(tunekit.__version__)",
    # with whichever python3 comes first on PATH (the version needs neither numpy nor pandas).
    package_parent = os.path.dirname(os.path.dirname(os.path.abspath(tunekit.__file__)))
    r = subprocess.run(["bash", "-c", f"export PYTHONPATH={shlex.quote(package_parent)} && "
                        "python3 -c 'import tunekit; print(tunekit.__version__)'"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert cli("--version")[1].strip() == f"tunekit {r.stdout.strip()}"
