"""What the Python module's tests share: the tunekit executable they compare with (TUNEKIT_EXE,
default build/apps/tunekit) and the data sets the command's own tests use."""

import json
import os
import subprocess

import pytest

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
DATASETS = os.path.join(ROOT, "datasets")
TUNEKIT = os.environ.get("TUNEKIT_EXE", os.path.join(ROOT, "build", "apps", "tunekit"))


def dataset(rel):
    return os.path.join(DATASETS, rel)


def cli(*args, check=True):
    """Runs the tunekit command; (exit code, stdout, stderr)."""
    r = subprocess.run([TUNEKIT, *map(str, args)], capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"tunekit {' '.join(map(str, args))}: exit {r.returncode}\n{r.stderr}")
    return r.returncode, r.stdout, r.stderr


def cli_results(*args):
    """The `results` of `tunekit ARGS --json`."""
    return json.loads(cli(*args, "--json")[1])["results"]


@pytest.fixture
def scratch(tmp_path):
    return tmp_path
