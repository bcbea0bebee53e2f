# The module's promises that are not numbers: an example in every docstring, the exceptions' places.
import re

import fvm
from conftest import run_cli

FUNCTIONS = ["read_surface", "write_surface", "find_calottes", "fit_sphere", "fit_plane", "calibrate", "calibrate_scans",
             "read_calibration", "verify", "stitch", "focus"]


def test_every_function_and_class_documents_an_example():
    for name in FUNCTIONS + ["Surface", "ShapeFit", "Calibration", "InputError", "NotConvergedError"]:
        doc = getattr(fvm, name).__doc__ or ""
        assert "Example" in doc and ">>> " in doc, name
    for method in ("correct", "save", "to_json"):
        assert ">>> " in getattr(fvm.Calibration, method).__doc__, method


def test_exceptions_are_what_scripts_catch():
    # Bad input is a ValueError (exit 1 of the CLI), non-convergence a RuntimeError (exit 3): distinct.
    assert issubclass(fvm.InputError, ValueError)
    assert issubclass(fvm.NotConvergedError, RuntimeError)
    assert not issubclass(fvm.NotConvergedError, ValueError)
    assert fvm.__version__.count(".") == 2


def test_version_names_the_release_and_commit_as_the_command_line_does():
    # fvm --version prints "fvm <release> (commit <commit>)" from the same generated source (core/version.h).
    assert re.fullmatch(r"[0-9]+\.[0-9]+\.[0-9]+", fvm.__version__)
    assert re.fullmatch(r"[0-9a-f]{12}(-dirty)?|unknown", fvm.__git_commit__)
    shown, _ = run_cli("--version")
    assert shown.strip() == f"fvm {fvm.__version__} (commit {fvm.__git_commit__})"
