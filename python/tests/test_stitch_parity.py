# fvm.stitch and the tiles jobs against the command line on the same input: every summary equals `fvm <job> --json`
# (less the keys that hold the paths of written files), the printed text and the written files are the command's.
# fvm.write_report writes the files `fvm stitch --report` writes; fvm.diagnose_tiles equals `fvm diagnose --scan --json`.
import json
import struct

import numpy as np
import pytest

import fvm
from conftest import REPO, SAMPLE, run_cli


def cli_json(*args):
    out, _ = run_cli(*args, "--json")
    return json.loads(out)


@pytest.fixture(scope="module")
def tile_set(tmp_path_factory):
    # 3 x 3 8-bit tiles of the dense texture with a stage error of 1.5 px: what tests/fvm/tiles_cli_test.cmake
    # stitches; written by Python, so the command reading them checks the set as well.
    d = tmp_path_factory.mktemp("set")
    fvm.tiles_synthesize(d, rows=3, cols=3, tile_px=256, bits=8, seed=4)
    return d


@pytest.mark.parametrize("options", [[], ["--pixel-mm", "0.001"], ["--distortion", "2", "--pixel-mm", "0.001"],
                                     ["--pixel-mm", "0.001", "--distortion"]],
                         ids=["grid", "pixel-mm", "distortion", "distortion-default-order"])
def test_stitch_summary_equals_the_command_json(tile_set, tmp_path, options):
    layout = tile_set / "layout.csv"
    doc = cli_json("stitch", "--layout", layout, "--overlap", "20", "-o", tmp_path / "p.csv", *options)
    keywords = {"pixel_mm": 0.001} if "--pixel-mm" in options else {}
    if "--distortion" in options:
        keywords["distortion"] = 2 if "2" in options else True
    result = fvm.stitch(layout, overlap=20, **keywords)
    assert result.summary == doc
    if "--distortion" in options and "2" not in options:
        # The default order (3): the terms a grid's overlaps see only as a stretch or shear are held, and named.
        field = result.summary["distortion"]
        assert field["order"] == 3
        assert field["held_terms"] == ["k1", "dx_x3", "dx_y3", "dy_x3"]
        assert all(t["value_px"] == 0 and t["u_px"] == 0 for t in field["terms"] if t["name"] in field["held_terms"])
        assert field["overlap_ncc_after"] > field["overlap_ncc_before"]
    # The arrays are the positions the command writes (4 decimals in its CSV).
    rows = np.genfromtxt(tmp_path / "p.csv", delimiter=",", names=True, dtype=None, encoding=None)
    np.testing.assert_allclose(result["positions"], np.c_[rows["x"], rows["y"]], atol=5e-5)


def report_files(directory):
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir())}


def test_stitch_report_is_the_commands(tile_set, tmp_path):
    # With a field: the page, the tiles and pairs plot and the field's plot, byte for byte.
    layout = tile_set / "layout.csv"
    run_cli("stitch", "--layout", layout, "--overlap", "20", "-o", tmp_path / "p.csv", "--pixel-mm", "0.001",
            "--distortion", "--report", tmp_path / "cli")
    result = fvm.stitch(layout, overlap=20, pixel_mm=0.001, distortion=True)
    assert result.has_report
    fvm.write_report(result, tmp_path / "py")
    cli, py = report_files(tmp_path / "cli"), report_files(tmp_path / "py")
    assert sorted(cli) == ["field.svg", "index.html", "positions.svg"]
    assert cli == py


def test_diagnose_tiles_summary_equals_the_command_json(tmp_path):
    # Scans through a known radial field (k1 = 2 px): the field named, as the command names it.
    run_cli("simulate", "scan", "-o", tmp_path / "s", "--seed", "2", "--tile-px", "256", "--length-mm", "20",
            "--validation", "1", "--distortion", "2")
    pixel = json.loads((tmp_path / "s" / "truth.json").read_text())["pixel_mm"]
    scans = [tmp_path / "s" / f"{name}.csv" for name in ("row", "column", "diagonal")]
    doc = cli_json("diagnose", *[a for s in scans for a in ("--scan", s)], "--pixel-mm", pixel)
    result = fvm.diagnose_tiles(scans=scans, pixel_mm=pixel)
    assert result.summary == doc
    assert result["effect"] == "field_distortion"
    assert result["after"]["rms_px"] < 0.2 * result["before"]["rms_px"]


def test_stitch_text_is_the_commands_less_its_file_line(tile_set, tmp_path):
    out, _ = run_cli("stitch", "--layout", tile_set / "layout.csv", "--overlap", "20", "-o", tmp_path / "p.csv")
    assert out == str(fvm.stitch(tile_set / "layout.csv", overlap=0.2)) + f"positions written to {tmp_path / 'p.csv'}\n"


def write_rgb_tiff(path, rgb):
    """An 8-bit RGB TIFF, uncompressed, one strip (TIFF 6.0): written here, not by fvm, to check fvm's reader."""
    rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
    rows, cols, _ = rgb.shape
    pixels = rgb.tobytes()
    entries = [(256, 4, 1, cols), (257, 4, 1, rows), (258, 3, 3, None), (259, 3, 1, 1), (262, 3, 1, 2),
               (273, 4, 1, None), (277, 3, 1, 3), (278, 4, 1, rows), (279, 4, 1, len(pixels)), (284, 3, 1, 1)]
    bits_offset = 8 + 2 + 12 * len(entries) + 4
    data_offset = bits_offset + 6
    ifd = struct.pack("<H", len(entries))
    for tag, kind, count, value in entries:
        value = bits_offset if tag == 258 else data_offset if tag == 273 else value
        packed = struct.pack("<HH", value, 0) if kind == 3 and count == 1 else struct.pack("<I", value)
        ifd += struct.pack("<HHI", tag, kind, count) + packed
    ifd += struct.pack("<I", 0)
    with open(path, "wb") as f:
        f.write(b"II*\x00" + struct.pack("<I", 8) + ifd + struct.pack("<HHH", 8, 8, 8) + pixels)


def test_colour_tiles_stitch_as_the_command_reads_them(tmp_path):
    # A 2 x 2 colour set: the channels differ (red darker, blue lighter) around one texture, so that a reader taking
    # one channel, or refusing three, fails. The command reads the files; Python the same files, and the arrays.
    rng = np.random.default_rng(5)
    scene = 60 + 120 * rng.random((400, 400))
    from synthetic import gaussian_blur
    scene = 128 + 40 * gaussian_blur(scene - scene.mean(), 1.5) / gaussian_blur(scene - scene.mean(), 1.5).std()
    offsets = {(0, 0): (20, 20), (0, 1): (172, 22), (1, 0): (18, 171), (1, 1): (171, 173)}
    arrays, layout, lines = [], [], ["file,row,col"]
    for (r, c), (x, y) in offsets.items():
        grey = np.clip(np.rint(scene[y:y + 190, x:x + 190]), 20, 235)
        rgb = np.stack([grey - 15, grey, grey + 15], axis=-1).astype(np.uint8)
        write_rgb_tiff(tmp_path / f"t{r}{c}.tif", rgb)
        arrays.append(rgb)
        layout.append((r, c))
        lines.append(f"t{r}{c}.tif,{r},{c}")
    (tmp_path / "layout.csv").write_text("\n".join(lines) + "\n")
    doc = cli_json("stitch", "--layout", tmp_path / "layout.csv", "--overlap", "20", "-o", tmp_path / "p.csv")
    from_files = fvm.stitch(tmp_path / "layout.csv", overlap=20)
    assert from_files.summary == doc and doc["pairs_accepted"] == 4
    from_arrays = fvm.stitch(arrays, layout, overlap=0.2)
    # The same tiles: the grey of each pixel is the channels' mean, here the middle channel exactly.
    np.testing.assert_allclose(from_arrays["positions"], from_files["positions"], atol=1e-6)
    truth = np.array([[x - 20, y - 20] for (x, y) in offsets.values()], dtype=float)
    np.testing.assert_allclose(from_arrays["positions"], truth, atol=0.05)
    # Alpha is left out, as the command leaves out a file's alpha channel.
    rgba = [np.concatenate([a, np.zeros(a.shape[:2] + (1,), np.uint8)], axis=-1) for a in arrays]
    assert fvm.stitch(rgba, layout, overlap=0.2).summary == from_arrays.summary


def test_stitch_refuses_what_the_command_refuses(tile_set):
    with pytest.raises(fvm.InputError, match="--min-quality"):
        fvm.stitch(tile_set / "layout.csv", overlap=20, min_quality=2)
    with pytest.raises(fvm.InputError, match="distortion"):
        fvm.stitch(tile_set / "layout.csv", overlap=20, distortion=9)


def plan_summary_less_paths(doc):
    for path in doc.get("paths", []):
        path.pop("layout")
    return doc


@pytest.mark.parametrize("case", ["artefact", "region", "features", "calibration-scan"])
def test_tiles_plan_equals_the_command(tmp_path, case):
    cli, py = tmp_path / "cli", tmp_path / "py"
    cli.mkdir(), py.mkdir()
    if case == "artefact":
        args = ["--lens", "10x", "--artefact", "grid6x6", "--overlap", "13"]
        keywords = dict(lens="10x", artefact="grid6x6", overlap=13)
    elif case == "region":
        args = ["--fov-mm", "1.3", "--region", "0,0,4,3", "--overlap", "10", "--tile-px", "2048x1536",
                "--bytes-per-pixel", "3", "--seconds-per-tile", "2.5"]
        keywords = dict(fov_mm=1.3, region=(0, 0, 4, 3), overlap=0.1, tile_px=(2048, 1536), bytes_per_pixel=3,
                        seconds_per_tile=2.5)
    elif case == "features":
        args = ["--features", SAMPLE / "val-01.free.csv", "--radius-mm", "0.5", "--overlap", "15"]
        keywords = dict(features=SAMPLE / "val-01.free.csv", radius_mm=0.5, overlap=15)
    else:
        args = ["--calibration-scan", "--lens", "5x", "--overlap", "25", "--length-mm", "30", "--heights", "-50,-40",
                "--travel", "100x80"]
        keywords = dict(calibration_scan=True, lens="5x", overlap=25, length_mm=30, heights=[-50, -40],
                        travel=(100, 80))
    if case == "calibration-scan":
        files = ["row.csv", "column.csv", "diagonal.csv", "row-z2.csv"]
        doc = cli_json("tiles", "plan", *args, "--scan-dir", cli)
        result = fvm.tiles_plan(**keywords, scan_dir=py)
        assert [p["layout"] for p in result.summary["paths"]][:3] == [str(py / f) for f in files[:3]]
    else:
        files = ["stitched.csv"] + (["free.csv"] if case != "region" else [])
        outputs = ["-o", cli / "stitched.csv"] + (["--free-layout", cli / "free.csv"] if case != "region" else [])
        doc = cli_json("tiles", "plan", *args, *outputs)
        result = fvm.tiles_plan(**keywords, layout=py / "stitched.csv",
                                free_layout=py / "free.csv" if case != "region" else None)
    assert plan_summary_less_paths(result.summary) == plan_summary_less_paths(doc)
    for f in files:
        assert (py / f).read_bytes() == (cli / f).read_bytes(), f
    text, _ = run_cli("tiles", "plan", *args)
    assert str(fvm.tiles_plan(**keywords)) == text


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    path = tmp_path_factory.mktemp("cal") / "cal.json"
    run_cli("calibrate", SAMPLE, "--model", "27", "-o", path)
    return path


@pytest.mark.parametrize("render", [False, True], ids=["coordinates", "rendered"])
def test_tiles_simulate_equals_the_command(calibration, tmp_path, render):
    args = ["--lens", "5x", "--overlap", "30", "--from", "-150,-110,-50", "--to", "-135,-110,-50"]
    keywords = dict(lens="5x", overlap=30, from_=[-150, -110, -50], to=[-135, -110, -50])
    if render:
        args += ["--render", "--tile-px", "128", "--seed", "3", "--tiles", tmp_path / "cli"]
        keywords.update(render=True, tile_px=128, seed=3, tiles=tmp_path / "py")
    doc = cli_json("tiles", "simulate", "--calibration", calibration, *args)
    result = fvm.tiles_simulate(calibration, **keywords)
    assert result.summary == doc  # its one path, "calibration", is the same file named the same way
    if render:
        assert (tmp_path / "py" / "layout.csv").read_bytes() == (tmp_path / "cli" / "layout.csv").read_bytes()
    else:
        text, _ = run_cli("tiles", "simulate", "--calibration", calibration, *args)
        assert str(result) == text


@pytest.mark.parametrize("args,keywords", [
    (["--rows", "2", "--cols", "3", "--tile-px", "200", "--overlap", "25", "--seed", "7"],
     dict(rows=2, cols=3, tile_px=200, overlap=25, seed=7)),
    (["--texture", "sparse", "--seed", "5"], dict(texture="sparse", seed=5)),
    (["--artefact", "grid6x6", "--rows", "2", "--cols", "2", "--tile-px", "128", "--seed", "2"],
     dict(artefact="grid6x6", rows=2, cols=2, tile_px=128, seed=2)),
], ids=["waves", "sparse", "heights"])
def test_tiles_synthesize_writes_the_commands_files(tmp_path, args, keywords):
    out, _ = run_cli("tiles", "synthesize", "-o", tmp_path / "cli", *args)
    result = fvm.tiles_synthesize(tmp_path / "py", **keywords)
    assert str(result) == out.replace(str(tmp_path / "cli"), str(tmp_path / "py"))
    names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "py").iterdir())
    for name in [n for n in names if n.endswith(".csv")]:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # The tiles themselves: stitching either set gives the same document (TIFF headers carry the time of writing).
    overlap = "6" if keywords.get("texture") == "sparse" else "25" if "overlap" in keywords else "20"
    doc = cli_json("stitch", "--layout", tmp_path / "cli" / "layout.csv", "--overlap", overlap, "-o", tmp_path / "p.csv")
    assert fvm.stitch(tmp_path / "py" / "layout.csv", overlap=float(overlap)).summary == doc


def test_a_fiji_tile_configuration_stitches_as_the_command_reads_it(tile_set, tmp_path):
    # Fiji's Grid stitching's TileConfiguration.txt for the set (serpentine, at the nominal grid): read as a layout
    # by both front ends, the same summary; positions of the tiles as with the CSV layout.
    lines = ["# Define the number of dimensions we are working on", "dim = 2", "",
             "# Define the image coordinates"]
    for row in range(3):
        for k in range(3):
            col = 2 - k if row == 1 else k
            lines.append(f"tile_r{row:03d}_c{col:03d}.tif; ; ({col * 204.8}, {row * 204.8})")
    config = tile_set / "TileConfiguration.txt"
    config.write_text("\n".join(lines) + "\n")
    doc = cli_json("stitch", "--layout", config, "--overlap", "20", "-o", tmp_path / "p.csv")
    result = fvm.stitch(config, overlap=20)
    assert result.summary == doc
    assert doc["nominal"] == "stage"
    grid = fvm.stitch(tile_set / "layout.csv", overlap=20)
    names = [f"tile_r{r:03d}_c{c:03d}.tif" for r in range(3) for c in range(3)]
    fiji_order = [l.split(";")[0] for l in lines[4:]]
    fiji_xy = {f: result["positions"][i] for i, f in enumerate(fiji_order)}
    csv_rows = [l.split(",")[0] for l in (tile_set / "layout.csv").read_text().splitlines() if l and not l.startswith("#")][1:]
    for i, f in enumerate(csv_rows):
        np.testing.assert_allclose(fiji_xy[f.split("/")[-1]], grid["positions"][i], atol=1e-3)
    assert set(names) == set(fiji_xy)
