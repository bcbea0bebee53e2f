# Python's fit, focus, info, diff and simulators give the same answers as the command line: each result's summary
# equals `json.loads` of `fvm <job> ... --json` on the same input, less the keys that hold the command's file paths
# (the simulators have no --json: their summary is the truth.json they write, and Python writes the same files).
import json
import pathlib

import numpy as np
import pytest

import fvm
from conftest import REPO, run_cli
from synthetic import gaussian_blur, texture
from tiff import write_float_tiff

STRATEGIES = REPO / "samples" / "stitching-strategies"


def cli_json(*args, paths=()):
    """`fvm ARGS --json` as a dict, without the keys that name the command's files."""
    doc = json.loads(run_cli(*args, "--json")[0])
    for key in paths:
        doc.pop(key, None)
    return doc


def same_files(a, b, skip=()):
    """Every file under a and b is there in both, byte for byte (suffixes in skip: only present)."""
    names_a = sorted(p.relative_to(a) for p in a.rglob("*") if p.is_file())
    names_b = sorted(p.relative_to(b) for p in b.rglob("*") if p.is_file())
    assert names_a == names_b
    for name in names_a:
        if name.suffix not in skip:
            assert (a / name).read_bytes() == (b / name).read_bytes(), name


@pytest.fixture(scope="module")
def batch(tmp_path_factory):
    """A raw-export batch (x3p surfaces of bar17 placements), written by Python and by the command line."""
    root = tmp_path_factory.mktemp("batch")
    options = dict(seed=7, validation_placements=1, surfaces="x3p", surface_pixel_mm=0.1)
    result = fvm.simulate_batch(root / "py", **options)
    run_cli("simulate", "fvm-batch", "-o", root / "cli", "--seed", 7, "--validation-placements", 1,
            "--surfaces", "x3p", "--surface-pixel-mm", 0.1)
    return root, result


def test_simulate_batch_writes_what_the_command_writes(batch):
    root, result = batch
    assert result.summary == json.loads((root / "cli" / "truth.json").read_text())
    assert str(result).startswith("simulated 4 placements (68 centres) into ")
    same_files(root / "py", root / "cli", skip={".x3p"})  # X3P archives carry their writing date
    for x3p in (root / "cli").glob("*.x3p"):
        a, b = fvm.read_surface(x3p), fvm.read_surface(root / "py" / x3p.name)
        assert np.array_equal(a.heights, b.heights, equal_nan=True) and a.spacing == b.spacing and a.origin == b.origin


def test_fit_of_calottes_and_its_centre_export_equal_the_command(batch, tmp_path):
    root, _ = batch
    surface = root / "cli" / "id-x.stitched.x3p"
    result = fvm.fit(surface, artefact="bar17", output=tmp_path / "py.csv")
    assert result.summary == cli_json("fit", surface, "--artefact", "bar17", "-o", tmp_path / "cli.csv",
                                      paths=("file", "output"))
    assert (tmp_path / "py.csv").read_bytes() == (tmp_path / "cli.csv").read_bytes()
    text = run_cli("fit", surface, "--artefact", "bar17")[0]
    assert str(result) == text
    found = fvm.find_calottes(fvm.read_surface(surface), artefact="bar17", name=str(surface))
    assert found["summary"] == result.summary


def test_fit_of_one_shape_equals_the_command(tmp_path):
    # 200 points on a 12.5 mm sphere cap with 1 um noise and five strays 50 um off: the robust search drops them.
    rng = np.random.default_rng(3)
    direction = rng.normal(size=(200, 3))
    direction[:, 2] = np.abs(direction[:, 2]) + 1.0
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    points = np.array([1.0, -2.0, 3.0]) + (12.5 + rng.normal(0, 1e-3, (200, 1))) * direction
    points[:5] += 0.05 * direction[:5]
    path = tmp_path / "cap.xyz"
    np.savetxt(path, points, fmt="%.9f")
    for shape, robust in (("sphere", False), ("sphere", True), ("plane", False)):
        args = ["fit", path, "--shape", shape] + (["--robust"] if robust else [])
        result = fvm.fit(path, shape=shape, robust=robust)
        assert result.summary == cli_json(*args, paths=("file",))
        assert str(result) == run_cli(*args)[0]
    assert fvm.fit(path, shape="sphere", robust=True)["outliers"] >= 5  # the strays, and what noise puts past 3 sigma


def test_info_equals_the_command(tmp_path):
    heights = np.fromfunction(lambda r, c: 1e-3 * np.sin(r / 7.0) * np.cos(c / 5.0), (40, 60))
    heights[3, 4] = np.nan
    path = tmp_path / "wave.x3p"
    fvm.write_surface(path, fvm.Surface(heights, spacing=(0.002, 0.003)))
    expected = cli_json("info", path, paths=("file",))
    assert fvm.info(path).summary == expected
    assert fvm.read_surface(path).summary == expected
    assert str(fvm.info(path)) == run_cli("info", path)[0]
    cloud = tmp_path / "points.xyz"
    np.savetxt(cloud, np.random.default_rng(1).random((50, 3)) * 1000.0, fmt="%.6f")  # in um
    assert fvm.info(cloud, unit="um").summary == cli_json("info", cloud, "--unit", "um", paths=("file",))


def test_focus_of_files_and_of_arrays_equals_the_command(tmp_path):
    # Two flat levels under a textured part, imaged at 13 focal planes 2 um apart, written as float TIFFs.
    rng = np.random.default_rng(4)
    rows, cols, step = 48, 64, 0.002
    truth = np.where(np.arange(cols)[None, :] < cols // 2, 0.008, 0.016) * np.ones((rows, 1))
    sharp = texture(rng, rows, cols, grain_px=2.0)
    z = np.arange(13) * step
    stack = np.empty((len(z), rows, cols), dtype=np.float32)
    for i, zi in enumerate(z):
        for level in (0.008, 0.016):
            stack[i][truth == level] = gaussian_blur(sharp, np.hypot(0.7, 500.0 * (zi - level)))[truth == level]
        write_float_tiff(tmp_path / f"s{i:02d}.tif", stack[i])
    expected = cli_json("focus", tmp_path, "-o", tmp_path / "h.x3p", "--z-step-mm", step, paths=("file",))
    r = fvm.focus_files(tmp_path, z_step_mm=step)
    assert r["summary"] == expected
    assert fvm.focus_files([tmp_path / f"s{i:02d}.tif" for i in range(13)], z_step_mm=step)["summary"] == expected
    assert fvm.focus(stack, z, dx_mm=0.001)["summary"] == expected
    slices = cli_json("focus", tmp_path, "-o", tmp_path / "h.x3p", "--measure", "tenengrad", "--window-px", 7,
                      paths=("file",))
    assert fvm.focus_files(tmp_path, measure="tenengrad", window_px=7)["summary"] == slices
    assert slices["z_unit"] == "slice" and slices["window"] == 7


@pytest.mark.parametrize("test,options", [("y", {}), ("x", {"pairs": "1:6", "xy": True})])
def test_diff_equals_the_command(test, options):
    a, b = STRATEGIES / "x" / "a.csv", STRATEGIES / test / ("a.csv" if test == "y" else "b.csv")
    args = ["diff", a, b] + (["--pairs", options["pairs"], "--xy"] if options else [])
    result = fvm.diff(a, b, **options)
    assert result.summary == cli_json(*args, paths=("ref", "test"))
    assert str(result) == run_cli(*args)[0]


def test_simulate_scan_writes_what_the_command_writes(batch, tmp_path):
    root, _ = batch
    truth = root / "cli" / "truth.json"
    result = fvm.simulate_scan(tmp_path / "py", calibration_truth=truth, tile_px=32, validation=5,
                               heights=[-50.0, -40.0], tiles="heights")
    run_cli("simulate", "scan", "-o", tmp_path / "cli", "--calibration-truth", truth, "--tile-px", 32,
            "--validation", 5, "--heights=-50,-40", "--tiles", "heights")
    assert result.summary == json.loads((tmp_path / "cli" / "truth.json").read_text())
    same_files(tmp_path / "py", tmp_path / "cli", skip={".tif"})  # TIFF tiles carry their writing date
