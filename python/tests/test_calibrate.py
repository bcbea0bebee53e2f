# fvm.calibrate against the command line on the bundled sample (samples/bar17): the same workflow, so the same bits.
import csv
import json

import numpy as np
import pytest

import fvm
from conftest import SAMPLE, run_cli


@pytest.fixture(scope="module")
def cli_doc():
    out, _ = run_cli("calibrate", SAMPLE, "--model", "27", "--json")
    return json.loads(out)


@pytest.fixture(scope="module")
def cal():
    return fvm.calibrate(str(SAMPLE), model=27)


def test_parameters_equal_the_command_lines_bit_for_bit(cal, cli_doc):
    # nlohmann-json writes the shortest text that reads back to the same double, so equality here is equality of
    # the doubles the two processes computed, not of rounded text.
    p = cal.parameters
    assert p["names"] == [q["name"] for q in cli_doc["parameters"]]
    assert p["state"] == [q["state"] for q in cli_doc["parameters"]]
    assert p["values"].tolist() == [q["value"] for q in cli_doc["parameters"]]
    assert p["u"].tolist() == [q["u"] for q in cli_doc["parameters"]]
    assert len(p["names"]) >= 27 and cal.model == "27"


def test_validation_figures_equal_the_command_lines(cal, cli_doc):
    judged, v = cal.summary["judged"], cli_doc["validation"]
    assert judged["held_out"] and judged["placements"] == v["placements"]
    for key in ("rigid", "distances"):
        assert judged[key]["rms_um"] == v[key]["rms_um"]
        assert judged["before"][key]["rms_um"] == v["before"][key]["rms_um"]
    assert judged["mean_um"] == v["mean_um"]
    assert judged["distance_error_max_um"]["after"] == v["distance_error_max_um"]["after"]
    # The correction works on held-out data: the distance errors shrink (README: 1.1 um after from tens before).
    assert judged["distances"]["rms_um"] < 0.2 * judged["before"]["distances"]["rms_um"]


def read_export(path):
    with open(path) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    return [int(r["id"]) for r in rows], np.array([[float(r[k]) for k in "xyz"] for r in rows])


def test_arrays_give_the_same_calibration_as_the_directory(cal):
    roles = json.loads((SAMPLE / "batch.json").read_text())
    placements = {}
    for name in roles["identify"] + roles["validate"]:
        ids, stitched = read_export(SAMPLE / f"{name}.stitched.csv")
        free_ids, free = read_export(SAMPLE / f"{name}.free.csv")
        order = [free_ids.index(i) for i in ids]
        placements[name] = {"ids": ids, "stitched": stitched, "free": free[order]}
    from_arrays = fvm.calibrate(placements, model=27, identify=roles["identify"], validate=roles["validate"])
    assert from_arrays.parameters["values"].tolist() == cal.parameters["values"].tolist()
    assert from_arrays.summary["judged"]["distances"] == cal.summary["judged"]["distances"]


def test_correct_equals_fvm_correct_with_the_saved_file(cal, tmp_path):
    saved = tmp_path / "cal.json"
    cal.save(saved)
    out, _ = run_cli("correct", "--calibration", saved, SAMPLE / "val-01.free.csv", "-o", tmp_path / "c.csv", "--json")
    doc = json.loads(out)
    ids, free = read_export(SAMPLE / "val-01.free.csv")
    corrected, u = cal.correct(free)
    assert [c["id"] for c in doc["centres"]] == ids
    assert corrected.tolist() == [[c["x"], c["y"], c["z"]] for c in doc["centres"]]
    assert (u * 1e3).tolist() == [c["u_um"] for c in doc["centres"]]
    # The file read back corrects the same way (its numbers round-trip exactly).
    again, _ = fvm.read_calibration(saved).correct(free)
    assert again.tolist() == corrected.tolist()


def test_bad_batches_raise_the_command_lines_messages(tmp_path):
    _, err = run_cli("calibrate", tmp_path / "none", "--model", "27", code=1)
    with pytest.raises(fvm.InputError) as raised:
        fvm.calibrate(str(tmp_path / "none"))
    assert err.strip() == f"fvm: error: {raised.value}"
    with pytest.raises(fvm.InputError, match="unknown model '8'"):
        fvm.calibrate(str(SAMPLE), model=8)
    with pytest.raises(fvm.InputError, match='both in "identify" and "validate"'):
        fvm.calibrate({"a": {"ids": [1, 2, 3], "stitched": np.eye(3), "free": np.eye(3)}}, identify=["a"], validate=["a"])


def test_raw_surface_exports_give_the_command_lines_calibration(tmp_path):
    # A batch of the instrument's raw X3P exports (simulated, coarse 0.1 mm pixels to keep it to seconds): the
    # calottes are searched in each surface as `fvm calibrate DIR` does, so the parameters are the same bits.
    raw = tmp_path / "raw"
    run_cli("simulate", "fvm-batch", "-o", raw, "--seed", "7", "--surfaces", "x3p", "--surface-pixel-mm", "0.1")
    out, _ = run_cli("calibrate", raw, "--model", "27", "--json")
    cli = json.loads(out)
    p = fvm.calibrate(str(raw), model=27).parameters
    assert p["names"] == [q["name"] for q in cli["parameters"]]
    assert p["values"].tolist() == [q["value"] for q in cli["parameters"]]
