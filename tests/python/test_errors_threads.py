"""Errors reach Python as exceptions with the command's one line; analyses run in threads give
the results they give one after the other."""

import concurrent.futures
import re

import pytest

import tunekit
from conftest import cli, dataset


def error_line(*args):
    """The command's error line without its "tunekit: error: " prefix."""
    code, _, err = cli(*args, check=False)
    line = err.strip().splitlines()[-1]
    assert line.startswith("tunekit: error: ")
    return code, line[len("tunekit: error: "):]


def test_bad_input_is_a_value_error_with_the_commands_message(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("time,force\n0,1\n1,abc\n")
    code, line = error_line("step", bad, "--output", "force", "--step-time", "0", "--step-size", "1")
    assert code == 2
    with pytest.raises(ValueError) as e:
        tunekit.step(bad, output="force", step_time=0, step_size=1)
    assert str(e.value) == line


def test_a_fit_that_failed_is_a_fit_error_with_the_commands_message(tmp_path):
    # Too short to see tau: after the step the output is a ramp that never bends.
    path = tmp_path / "ramp.csv"
    rows = [(i * 0.01, 1.0 if i < 100 else 2.0, 1.0 if i < 100 else 1.0 + 0.01 * (i - 100) + 0.0005 * (i % 2))
            for i in range(200)]
    path.write_text("time (s),feed (mm/s),force (N)\n" + "".join(f"{t!r},{u!r},{y!r}\n" for t, u, y in rows))
    code, line = error_line("step", path, "--time", "time", "--input", "feed", "--output", "force")
    assert code == 1, line
    assert "not identifiable" in line
    with pytest.raises(tunekit.FitError) as e:
        tunekit.step(path, time="time", input="feed", output="force")
    assert isinstance(e.value, RuntimeError)
    assert str(e.value) == line


def test_an_unknown_option_is_a_value_error_naming_it():
    with pytest.raises(ValueError, match=re.escape("unknown option 'tua'")):
        tunekit.step(dataset("liquefier/synthetic_steps.csv"), output="force", tua=1)


def test_independent_analyses_in_threads_give_the_serial_results():
    jobs = [
        (tunekit.step, (dataset("liquefier/synthetic_steps.csv"),),
         dict(time="time", input="feed", output="force", step_at="first")),
        (tunekit.rheo, (dataset("rheology/peek_cross_wlf_synthetic.csv"),), dict(model="cross-wlf")),
        (tunekit.shaper, (dataset("klipper_spectra/resonances_x_20220317_143228.csv"),),
         dict(klipper_compatible=True)),
        (tunekit.freq, (dataset("liquefier/synthetic_chirp.csv"),),
         dict(time="time", input="feed", output="force", mode="h1", fit_tf="2,0", fmax=40)),
    ] * 2
    serial = [f(*a, **k).to_dict() for f, a, k in jobs]
    with concurrent.futures.ThreadPoolExecutor(max_workers=4) as pool:
        threaded = list(pool.map(lambda job: job[0](*job[1], **job[2]).to_dict(), jobs))
    assert threaded == serial
