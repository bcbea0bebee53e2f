# The machine-tool jobs of `import fvm` against the command line on the same inputs: every summary equals
# `fvm <job> --json` less the keys that name the command's files, and fvm.write_report writes the files --report
# writes, page for page.
import json
import pathlib

import pytest

import fvm
from conftest import SAMPLE, run_cli

STATIONS = """{"stations": [{"name": "A", "x": 1250, "y": -1699, "z": -1132},
              {"name": "B", "x": 3371, "y": 1975, "z": -1132},
              {"name": "C", "x": -871, "y": 1975, "z": -1132},
              {"name": "D", "x": -1309, "y": -727, "z": 1121}]}"""
PATHS = {"data", "readings", "output"}
TIMES = {"seconds", "propagation_seconds"}  # wall-clock, never equal between two runs


def cli_json(*args, drop=()):
    out, _ = run_cli(*args, "--json")
    return {k: v for k, v in json.loads(out).items() if k not in PATHS | set(drop)}


def summary(result, drop=()):
    return {k: v for k, v in result.summary.items() if k not in set(drop)}


@pytest.fixture(scope="module")
def work(tmp_path_factory):
    d = tmp_path_factory.mktemp("machine")
    run_cli("simulate", "tracker", "--seed", "1", "--tool", "0,0,100", "--validation", "mesh:250,250,200", "-o", d / "plan")
    run_cli("simulate", "tracker", "--machine", "400x400x200", "--points", "mesh:100,100,100", "--tool", "0,0,100",
            "--pose", "900,-900,400,0,0,30", "--validation", "mesh:100,100,50", "--seed", "1", "-o", d / "small")
    (d / "stations.json").write_text(STATIONS)
    run_cli("simulate", "tracker", "--seed", "1", "--tool", "0,0,100", "--stations", d / "stations.json", "-o", d / "net")
    run_cli("simulate", "testpiece", "-o", d / "tp", "--validation", "30,30,30")
    return d


def same_report(cli_dir, py_dir):
    names = sorted(p.name for p in pathlib.Path(cli_dir).iterdir())
    assert names == sorted(p.name for p in pathlib.Path(py_dir).iterdir())
    for name in names:
        if name.endswith((".html", ".csv")):
            assert (pathlib.Path(cli_dir) / name).read_text() == (pathlib.Path(py_dir) / name).read_text(), name


def test_verify_equals_the_command_line_with_its_report(work, tmp_path):
    readings, validation = str(work / "plan" / "readings.csv"), str(work / "plan" / "validation.csv")
    doc = cli_json("verify", readings, "--order", "2", "--tool", "0,0,100", "--validate", validation, "--report",
                   tmp_path / "cli")
    v = fvm.verify(readings, tool=(0, 0, 100), order=2, validate=validation)
    assert summary(v) == doc
    assert {"euler_xyz_deg", "u_translation_um", "u_rotation_urad"} <= set(v["pose"]) and "plausibility" in v.keys()
    fvm.write_report(v, tmp_path / "py")
    same_report(tmp_path / "cli", tmp_path / "py")
    out, _ = run_cli("verify", readings, "--order", "2", "--tool", "0,0,100", "--validate", validation)
    assert str(v) == out


def test_verify_auto_order_and_held_pose(work):
    readings = str(work / "plan" / "readings.csv")
    assert summary(fvm.verify(readings, tool=(0, 0, 100), order="auto")) == cli_json(
        "verify", readings, "--order", "auto", "--tool", "0,0,100")
    held = fvm.verify(readings, tool=(0, 0, 100), order=1, pose=(1100, -1000, 600, 63, 14, 35))
    assert summary(held) == cli_json("verify", readings, "--order", "1", "--tool", "0,0,100", "--pose", "1100,-1000,600,63,14,35")
    assert held["pose"]["estimated"] is False
    travel = fvm.verify(readings, tool=(0, 0, 100), order=1, machine=(0, 0, 0, 2500, 1500, 1200))
    assert summary(travel) == cli_json("verify", readings, "--order", "1", "--tool", "0,0,100", "--machine", "2500x1500x1200")


def test_verify_refuses_an_implausible_result_as_the_command_line_does(work):
    readings = str(work / "plan" / "readings.csv")
    _, err = run_cli("verify", readings, "--tool", "0,0,100", "--max-error-mm", "0.001", code=1)
    with pytest.raises(fvm.InputError, match="raise the bound with --max-error-mm") as refused:
        fvm.verify(readings, tool=(0, 0, 100), max_error_mm=0.001)
    assert str(refused.value) in err


def test_machine_uncertainty_equals_the_command_line_with_its_report(work, tmp_path):
    readings, validation = str(work / "small" / "readings.csv"), str(work / "small" / "validation.csv")
    doc = cli_json("uncertainty", readings, "--order", "2", "--tool", "0,0,100", "--runs", "12", "--seed", "3",
                   "--validate", validation, "--report", tmp_path / "cli", drop=TIMES)
    u = fvm.uncertainty(readings, tool=(0, 0, 100), order=2, runs=12, seed=3, validate=validation)
    assert summary(u, TIMES) == doc
    fvm.write_report(u, tmp_path / "py")
    assert sorted(p.name for p in (tmp_path / "cli").iterdir()) == sorted(p.name for p in (tmp_path / "py").iterdir())
    for name in ("points.csv", "runs.csv"):
        assert (tmp_path / "cli" / name).read_text() == (tmp_path / "py" / name).read_text()


def test_stage_uncertainty_and_tracker_placement_equal_the_command_line(work):
    assert summary(fvm.uncertainty(str(SAMPLE), model="9", runs=4, seed=2), TIMES) == cli_json(
        "uncertainty", SAMPLE, "--model", "9", "--runs", "4", "--seed", "2", drop=TIMES)
    readings = str(work / "small" / "readings.csv")
    box = (700, -1100, 300, 1100, -700, 500)
    placed = fvm.uncertainty(readings, tool=(0, 0, 100), order=1, runs=3, place_tracker=box, place_steps=2, place_confirm=1)
    assert summary(placed, TIMES) == cli_json("uncertainty", readings, "--tool", "0,0,100", "--order", "1", "--runs", "3",
                                              "--place-tracker", ",".join(map(str, box)), "--place-steps", "2",
                                              "--place-confirm", "1", drop=TIMES)
    assert not placed.has_report


def test_multilaterate_equals_the_command_line(work):
    net = work / "net"
    for extra, keywords in (([], {}), (["--self-calibrate", "--angles"], {"self_calibrate": True, "angles": True})):
        stations = [] if extra else ["--stations", net / "stations.json"]
        doc = cli_json("multilaterate", net / "readings.csv", *stations, *extra, "--truth", net / "true_points.csv")
        r = fvm.multilaterate(str(net / "readings.csv"), stations="" if extra else str(net / "stations.json"),
                              truth=str(net / "true_points.csv"), **keywords)
        assert summary(r) == doc


def test_testpiece_jobs_equal_the_command_line_with_the_report(work, tmp_path):
    assert summary(fvm.testpiece_design()) == cli_json("testpiece", "design")
    tp = work / "tp"
    doc = cli_json("testpiece", "verify", tp / "measured.csv", "--order", "2", "--nominal", tp / "nominal.csv",
                   "--validate", tp / "validation.csv", "--report", tmp_path / "cli")
    r = fvm.testpiece_verify(str(tp / "measured.csv"), order=2, nominal=str(tp / "nominal.csv"),
                             validate=str(tp / "validation.csv"))
    assert summary(r) == doc
    fvm.write_report(r, tmp_path / "py")
    same_report(tmp_path / "cli", tmp_path / "py")


def test_simulations_write_what_the_command_line_writes(tmp_path):
    out, _ = run_cli("simulate", "testpiece", "-o", tmp_path / "cli_tp", "--proposed-series", "--points", "series", "--json")
    r = fvm.simulate_testpiece(str(tmp_path / "py_tp"), proposed_series=True, points="series")
    assert summary(r) == {k: v for k, v in json.loads(out).items() if k != "output"}
    for name in ("nominal.csv", "measured.csv", "truth.json"):
        assert (tmp_path / "cli_tp" / name).read_text() == (tmp_path / "py_tp" / name).read_text()
    out, _ = run_cli("simulate", "tracker", "--seed", "2", "--points", "cloud:500,500,400", "--validation", "diagonals:10",
                     "-o", tmp_path / "cli_plan")
    r = fvm.simulate_tracker(str(tmp_path / "py_plan"), seed=2, points="cloud:500,500,400", validation="diagonals:10")
    assert str(r) == out.replace(str(tmp_path / "cli_plan"), str(tmp_path / "py_plan"))
    for name in ("points.csv", "program.nc", "readings.csv", "validation.csv", "truth.json"):
        assert (tmp_path / "cli_plan" / name).read_text() == (tmp_path / "py_plan" / name).read_text(), name
    assert r.summary == json.loads((tmp_path / "cli_plan" / "truth.json").read_text())
