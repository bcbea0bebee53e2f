# fvm.compare, fvm.diagnose and fvm.correct against the command line on the same inputs: the same workflows and the
# same summaries (workflows::Summarize), so the same --json documents less the paths of the command's files, the same
# printed text, the same written files, and fvm.write_report writes what --report writes.
import json
import pathlib

import pytest

import fvm
from conftest import SAMPLE, run_cli


def cli_json(*args, paths=("batch", "input", "output", "layout")):
    out, _ = run_cli(*args, "--json")
    doc = json.loads(out)
    for key in paths:
        doc.pop(key, None)
    return doc


@pytest.fixture(scope="module")
def drift(tmp_path_factory):
    batch = tmp_path_factory.mktemp("drift") / "drift"
    run_cli("simulate", "fvm-batch", "-o", batch, "--seed", "7", "--hidden-effect", "thermal_drift")
    return batch


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    path = tmp_path_factory.mktemp("cal") / "cal.json"
    run_cli("calibrate", SAMPLE, "--model", "27", "-o", path)
    return path


def test_compare_equals_the_command_line(drift):
    doc = cli_json("compare", drift, "--models", "15,27", "--anchor", "first-tile")
    result = fvm.compare(str(drift), models=[15, 27], anchor="first-tile")
    assert result.summary == doc
    assert "batch" not in result.keys() and result["recommendation"] == doc["recommendation"]
    text, _ = run_cli("compare", drift, "--models", "15,27", "--anchor", "first-tile")
    assert str(result) == text
    assert fvm.compare(str(drift), models="15,27", anchor="first-tile").summary == doc
    assert not result.has_report


def test_diagnose_equals_the_command_line_and_writes_its_report(drift, tmp_path):
    doc = cli_json("diagnose", drift, "--model", "27", "--alpha", "0.02")
    result = fvm.diagnose(str(drift), model=27, alpha=0.02)
    assert result.summary == doc
    assert result["effect"] == "thermal_drift"
    text, _ = run_cli("diagnose", drift, "--model", "27", "--alpha", "0.02", "--report", tmp_path / "cli")
    assert str(result) + f"\nreport written to {tmp_path / 'cli'}/index.html\n" == text
    fvm.write_report(result, str(tmp_path / "py"))
    cli_files = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert cli_files == sorted(p.name for p in (tmp_path / "py").iterdir())
    assert "steps.svg" in cli_files
    for name in cli_files:  # neither the page nor the plots embed the report's own path
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name


def test_options_are_checked_naming_the_command_lines_option(drift):
    with pytest.raises(fvm.InputError, match="--models: '8'"):
        fvm.compare(str(drift), models=[8])
    with pytest.raises(fvm.InputError, match="--alpha"):
        fvm.diagnose(str(drift), alpha=0.9)
    with pytest.raises(fvm.InputError, match="--stitched-frame"):
        fvm.diagnose(str(drift), stitched_frame="sideways")


def test_correct_centres_equals_the_command_line(calibration, tmp_path):
    free = SAMPLE / "val-01.free.csv"
    for frame in ("stage", "first-tile"):
        cli_out, py_out = tmp_path / f"cli-{frame}.csv", tmp_path / f"py-{frame}.csv"
        doc = cli_json("correct", "--calibration", calibration, free, "-o", cli_out, "--frame", frame)
        result = fvm.correct(str(calibration), str(free), str(py_out), frame=frame)
        assert result.summary == doc
        assert py_out.read_bytes() == cli_out.read_bytes()


def test_correct_scans_equals_the_command_line(calibration, tmp_path):
    # A cloud in stage coordinates with one invalid point, and the same cloud with its origin elsewhere.
    cloud = tmp_path / "cloud.xyz"
    rows = [f"{-150 + 7.3 * i % 100:.6f} {-140 + 3.1 * i % 90:.6f} {-45 + 0.01 * i:.6f}" for i in range(120)]
    cloud.write_text("\n".join(rows + ["nan nan nan"]) + "\n")
    out = tmp_path / "out.ply"
    doc = cli_json("correct", "--calibration", calibration, cloud, "-o", out, "--frame", "first-tile")
    cli_bytes = out.read_bytes()
    result = fvm.correct(str(calibration), str(cloud), str(out), frame="first-tile")
    assert result.summary == doc and result["invalid"] == 1
    assert out.read_bytes() == cli_bytes
    text, _ = run_cli("correct", "--calibration", calibration, cloud, "-o", out, "--origin", "1,2,0")
    result = fvm.correct(str(calibration), str(cloud), str(out), origin=(1, 2, 0))
    assert str(result) == text


def test_correct_refuses_as_the_command_line_does(calibration, tmp_path):
    cloud = tmp_path / "far.xyz"
    cloud.write_text("0.5 0.5 0\n0.6 0.5 0\n")
    _, err = run_cli("correct", "--calibration", calibration, cloud, "-o", tmp_path / "x.ply", code=1)
    with pytest.raises(fvm.InputError) as raised:
        fvm.correct(str(calibration), str(cloud), str(tmp_path / "y.ply"))
    assert err.strip() == f"fvm: error: {raised.value}"
    assert not (tmp_path / "y.ply").exists()
