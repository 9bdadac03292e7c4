"""export from result objects designs what `tunekit export` designs from the same analyses'
results files, previews and writes through the same path; the history reads as the command's."""

import shutil

import pytest

import tunekit
from conftest import cli, cli_results, dataset

STEP = (dataset("liquefier/synthetic_steps.csv"), dict(time="time", input="feed", output="force", step_at="first"))
SHAPER = (dataset("klipper_spectra/resonances_x_20220317_143228.csv"), dict(klipper_compatible=True))


def analyses_and_their_files(tmp_path):
    """The step and shaper results from Python, and the same analyses' results files from the command."""
    step = tunekit.step(STEP[0], **STEP[1])
    shaper = tunekit.shaper(SHAPER[0], **SHAPER[1])
    step_json, shaper_json = tmp_path / "step.json", tmp_path / "shaper.json"
    cli("step", STEP[0], "--time", "time", "--input", "feed", "--output", "force", "--step-at", "first",
        "-o", step_json)
    cli("shaper", SHAPER[0], "--klipper-compatible", "-o", shaper_json)
    return (step, shaper), (str(step_json), str(shaper_json))


def test_export_designs_from_result_objects_what_the_command_designs_from_their_files(tmp_path):
    results, files = analyses_and_their_files(tmp_path)
    cfg = tmp_path / "printer.cfg"
    shutil.copy(dataset("firmware/printer.cfg"), cfg)
    before = cfg.read_text()
    options = ["--firmware", "klipper", "--config", cfg, "--profile", dataset("machines/sim.toml")]
    expected = cli_results("export", *options, *files)
    preview = tunekit.export(*results, origins=files, firmware="klipper", config=cfg,
                             profile=dataset("machines/sim.toml"))
    assert preview.to_dict() == expected
    assert cfg.read_text() == before  # a preview writes nothing
    assert "shaper_freq_x" in preview.text


def test_export_writes_as_the_command_writes(tmp_path):
    results, files = analyses_and_their_files(tmp_path)
    by_python, by_cli = tmp_path / "python.cfg", tmp_path / "cli.cfg"
    shutil.copy(dataset("firmware/printer.cfg"), by_python)
    shutil.copy(dataset("firmware/printer.cfg"), by_cli)
    cli("export", "--firmware", "klipper", "--config", by_cli, "--profile", dataset("machines/sim.toml"), *files,
        "--write")
    written = tunekit.export(*results, origins=files, firmware="klipper", config=by_python,
                             profile=dataset("machines/sim.toml"), write=True)
    assert written.exit_code == 0
    assert by_python.read_text() == by_cli.read_text() != open(dataset("firmware/printer.cfg")).read()
    # From the results files the command wrote, too.
    again = tmp_path / "again.cfg"
    shutil.copy(dataset("firmware/printer.cfg"), again)
    tunekit.export(*files, firmware="klipper", config=again, profile=dataset("machines/sim.toml"), write=True)
    assert again.read_text() == by_cli.read_text()


def test_export_refuses_results_it_cannot_design_from(tmp_path):
    rheo = tunekit.rheo(dataset("rheology/peek_cross_wlf_synthetic.csv"), model="cross-wlf")
    cfg = tmp_path / "printer.cfg"
    shutil.copy(dataset("firmware/printer.cfg"), cfg)
    with pytest.raises(ValueError, match="results of 'rheo' cannot be designed from here"):
        tunekit.export(rheo, firmware="klipper", config=cfg)


def test_the_history_reads_as_the_command_reads_it(tmp_path):
    db = tmp_path / "history.sqlite"
    for _ in range(2):
        cli("step", STEP[0], "--time", "time", "--input", "feed", "--output", "force", "--step-at", "first",
            "--record", "--machine-id", "printer-1", "--db", db)
    assert tunekit.history_list(db) == cli_results("history", "list", "--db", db)
    listed = tunekit.history_list(db, ["printer-1"])
    assert listed == cli_results("history", "list", "--machine", "printer-1", "--db", db)
    first = listed["records"]["printer-1"][0]["record_id"]
    assert tunekit.history_show(first, db) == cli_results("history", "show", first, "--db", db)
    records = tunekit.history_records("printer-1", db)
    try:
        import pandas
        assert isinstance(records, pandas.DataFrame) and list(records["record_id"]) == [
            r["record_id"] for r in listed["records"]["printer-1"]]
    except ImportError:
        assert records == listed["records"]["printer-1"]
    assert len(records) == 2
