# fvm.calibrate and fvm.calibrate_scans against `fvm calibrate` on the same inputs (issue 48): the summary is the
# --json document, save() writes the file -o writes, and fvm.write_report writes the files --report writes. Both
# front ends are given the same path strings, so even the keys that name the user's files (batch, raw_exports'
# files and centres_dir, validation's batch) are equal; the report pages name the batch or the scans in their title
# and so do both. A batch with and without validation placements, a batch of raw surface exports, grey stitched
# scans judged on an artefact batch, and scans with the objective's field distortion identified.
import filecmp
import json
import shutil

import pytest

import fvm
from conftest import SAMPLE, run_cli


def cli_calibrate(tmp_path, name, *args):
    """`fvm calibrate ARGS --json -o F --report D`: (document printed, file written, report dir)."""
    written, report = tmp_path / f"{name}.cli.json", tmp_path / f"{name}.cli-report"
    out, _ = run_cli("calibrate", *args, "--json", "-o", written, "--report", report)
    return json.loads(out), written, report


def same_files(python_result, tmp_path, name, written, report):
    saved, python_report = tmp_path / f"{name}.py.json", tmp_path / f"{name}.py-report"
    python_result.save(saved)
    assert saved.read_bytes() == written.read_bytes()
    fvm.write_report(python_result, python_report)
    names = sorted(p.name for p in report.iterdir() if p.is_file())
    assert names == sorted(p.name for p in python_report.iterdir())
    assert "index.html" in names
    match, mismatch, errors = filecmp.cmpfiles(report, python_report, names, shallow=False)
    assert mismatch == [] and errors == [], mismatch + errors


def test_batch_with_validation_placements(tmp_path):
    cli, written, report = cli_calibrate(tmp_path, "bar17", SAMPLE, "--model", "27")
    cal = fvm.calibrate(str(SAMPLE), model=27)
    assert cal.summary == cli
    assert "validation" in cal.keys() and cal["validation"]["placements"] == cli["validation"]["placements"]
    same_files(cal, tmp_path, "bar17", written, report)
    # The printed table is the summary's text.
    out, _ = run_cli("calibrate", SAMPLE, "--model", "27")
    assert out == str(cal)


def test_batch_without_batch_json_judges_its_identification_placements_in_the_report(tmp_path):
    batch = tmp_path / "pairs"
    batch.mkdir()
    for f in SAMPLE.glob("*.csv"):
        shutil.copy(f, batch)
    args = ["--model", "15", "--anchor", "first-tile", "--loss", "huber", "--stitched-frame", "translated"]
    cli, written, report = cli_calibrate(tmp_path, "pairs", batch, *args)
    cal = fvm.calibrate(str(batch), model=15, anchor="first-tile", loss="huber", stitched_frame="translated")
    assert "validation" not in cli and cal.summary == cli
    same_files(cal, tmp_path, "pairs", written, report)


def test_raw_surface_exports(tmp_path):
    raw = tmp_path / "raw"
    run_cli("simulate", "fvm-batch", "-o", raw, "--seed", "5", "--validation-placements", "2", "--surfaces", "x3p",
            "--surface-pixel-mm", "0.1", "--surface-noise-um", "3")
    centres = tmp_path / "centres"
    cli, written, report = cli_calibrate(tmp_path, "raw", raw, "--model", "27", "--centres-dir", centres)
    cli_centres = {p.name: p.read_bytes() for p in centres.iterdir()}
    shutil.rmtree(centres)
    cal = fvm.calibrate(str(raw), model=27, centres_dir=str(centres))
    assert cal.summary == cli and len(cli["raw_exports"]["exports"]) == 10  # 5 placements, 2 exports each
    assert {p.name: p.read_bytes() for p in centres.iterdir()} == cli_centres
    same_files(cal, tmp_path, "raw", written, report)


@pytest.fixture(scope="module")
def scans(tmp_path_factory):
    d = tmp_path_factory.mktemp("scans")
    run_cli("simulate", "scan", "-o", d / "grey", "--seed", "1", "--tile-px", "128", "--length-mm", "30",
            "--validation", "5")
    run_cli("simulate", "scan", "-o", d / "field", "--seed", "2", "--tile-px", "128", "--length-mm", "30",
            "--validation", "5", "--distortion", "2")
    pixel = json.loads((d / "grey" / "truth.json").read_text())["pixel_mm"]
    return d, pixel


def layouts(d):
    return [str(d / f"{path}.csv") for path in ("row", "column", "diagonal")]


def scan_args(d, pixel):
    return [a for layout in layouts(d) for a in ("--scan", layout)] + ["--pixel-mm", repr(pixel)]


def test_scans_judged_on_an_artefact_batch(scans, tmp_path):
    d, pixel = scans
    args = scan_args(d / "grey", pixel) + ["--pixel-u-mm", "1e-05", "--model", "15", "--validate", str(SAMPLE)]
    cli, written, report = cli_calibrate(tmp_path, "scans", *args)
    cal = fvm.calibrate_scans(layouts(d / "grey"), pixel_mm=pixel, pixel_u_mm=1e-5, model=15, validate=str(SAMPLE))
    assert cal.summary == cli and cal["validation"]["batch"] == str(SAMPLE)
    same_files(cal, tmp_path, "scans", written, report)
    out, _ = run_cli("calibrate", *args)
    assert out == str(cal)


def test_scans_with_the_field_distortion(scans, tmp_path):
    d, pixel = scans
    cli_field, py_field = tmp_path / "cli-field.json", tmp_path / "py-field.json"
    out, _ = run_cli("calibrate", *scan_args(d / "field", pixel), "--model", "15", "--distortion",
                     "--save-distortion", cli_field, "--json")
    cal = fvm.calibrate_scans(layouts(d / "field"), pixel_mm=pixel, model=15, distortion=True,
                              save_distortion=str(py_field))
    assert cal.summary == json.loads(out) and cal["distortion"]["identified"]
    assert py_field.read_bytes() == cli_field.read_bytes()
    # The saved field, taken instead of identified.
    out, _ = run_cli("calibrate", *scan_args(d / "field", pixel), "--model", "15", "--distortion-file", cli_field,
                     "--json")
    again = fvm.calibrate_scans(layouts(d / "field"), pixel_mm=pixel, model=15, distortion_file=str(cli_field))
    assert again.summary == json.loads(out) and not again["distortion"]["identified"]
    # Without --validate there is nothing held out to report.
    assert not cal.has_report


def test_scan_options_are_refused_as_the_command_line_refuses_them(scans):
    d, pixel = scans
    _, err = run_cli("calibrate", *scan_args(d / "grey", 0.0)[:-2], code=1)
    with pytest.raises(fvm.InputError) as raised:
        fvm.calibrate_scans(layouts(d / "grey"), pixel_mm=0.0)
    assert err.strip() == f"fvm: error: {raised.value}"
    with pytest.raises(fvm.InputError, match="--distortion 9: give the polynomial order"):
        fvm.calibrate_scans(layouts(d / "grey"), pixel_mm=pixel, distortion=9)
    with pytest.raises(fvm.InputError, match="--distortion and --distortion-file"):
        fvm.calibrate_scans(layouts(d / "grey"), pixel_mm=pixel, distortion=True, distortion_file="f.json")
