# Shared paths for the tests of `import fvm`: run from the repository root as
#   PYTHONPATH=build/python python3 -m pytest -q python/tests
# (run.sh quick and test do). FVM_BUILD_DIR names another build tree (its fvm/fvm is the CLI compared against).
import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
BUILD = pathlib.Path(os.environ.get("FVM_BUILD_DIR", REPO / "build"))
CLI = BUILD / "fvm" / "fvm"
SAMPLE = REPO / "samples" / "bar17"


def run_cli(*args, code=0):
    """Runs the fvm executable; returns (stdout, stderr) after checking the exit code."""
    if not CLI.exists():
        pytest.skip(f"{CLI} is not built")
    done = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True)
    assert done.returncode == code, f"fvm {' '.join(map(str, args))}: exit {done.returncode}\n{done.stderr}"
    return done.stdout, done.stderr
