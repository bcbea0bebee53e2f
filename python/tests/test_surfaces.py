# Surfaces read and written, the plugin rule at import, and calottes found on a height map generated here.
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import fvm
from conftest import run_cli
from tiff import write_float_tiff

HERE = os.path.dirname(__file__)


def test_import_loads_neither_openimageio_nor_pcl_until_a_tiff_is_read(tmp_path):
    # A fresh interpreter: this one may already have read an image in another test.
    heights = np.arange(12, dtype=np.float32).reshape(3, 4) * 0.001
    write_float_tiff(tmp_path / "h.tif", heights)
    script = (
        "import json, sys\n"
        "def heavy():\n"
        "    with open('/proc/self/maps') as f:\n"
        "        return sorted({l.split()[-1].rsplit('/', 1)[-1] for l in f if 'libOpenImageIO' in l or 'libpcl' in l})\n"
        "import fvm\n"
        "at_import = heavy()\n"
        "s = fvm.read_surface(sys.argv[1], dx_mm=0.002)\n"
        "print(json.dumps({'import': at_import, 'read': heavy(), 'heights': s.heights.tolist()}))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "FVM_PLUGIN_DIR"}  # the loader finds the plugin itself
    done = subprocess.run([sys.executable, "-c", script, str(tmp_path / "h.tif")], capture_output=True, text=True, env=env)
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout)
    assert seen["import"] == []
    assert any(name.startswith("libOpenImageIO") for name in seen["read"])
    assert not any(name.startswith("libpcl") for name in seen["read"])  # a TIFF needs no PCL
    assert seen["heights"] == heights.astype(np.float64).tolist()  # float32 heights convert to double exactly


def test_a_tiff_reads_as_written_with_its_spacing(tmp_path):
    heights = np.random.default_rng(5).normal(0, 0.01, (20, 30)).astype(np.float32)
    heights[3, 4] = np.nan
    write_float_tiff(tmp_path / "h.tif", heights)
    s = fvm.read_surface(tmp_path / "h.tif", dx_mm=0.0025)
    assert s.format == "image" and s.spacing == (0.0025, 0.0025) and s.heights.shape == (20, 30)
    assert not s.mask[3, 4] and s.mask.sum() == 20 * 30 - 1
    np.testing.assert_array_equal(s.heights, heights.astype(np.float64))


def test_x3p_round_trip_keeps_float64_heights_bit_for_bit(tmp_path):
    z = np.random.default_rng(11).normal(0, 0.003, (40, 50))
    z[0, :5] = np.nan
    fvm.write_surface(tmp_path / "s.x3p", fvm.Surface(z, spacing=(0.001, 0.002), origin=(1.5, -2.0)))
    s = fvm.read_surface(tmp_path / "s.x3p")
    assert s.format == "x3p" and s.spacing == (0.001, 0.002) and s.origin == (1.5, -2.0)
    np.testing.assert_array_equal(s.mask, np.isfinite(z))
    # X3P holds metres: the mm -> m conversion has an exact inverse for ~98 % of doubles, the rest read back one
    # ulp away (imaging/io/x3p_writer.cc says so); the mask exactly.
    np.testing.assert_array_max_ulp(s.heights[s.mask], z[s.mask], maxulp=1)
    # The command line reads the same file the same way.
    out, _ = run_cli("info", tmp_path / "s.x3p", "--json")
    info = json.loads(out)
    assert (info["size_x"], info["size_y"], info["valid_points"]) == (50, 40, int(s.mask.sum()))
    assert info["z_max_mm"] == np.nanmax(z)


def test_missing_file_raises_the_command_lines_message(tmp_path):
    _, err = run_cli("info", tmp_path / "missing.x3p", code=1)
    with pytest.raises(fvm.InputError) as raised:
        fvm.read_surface(tmp_path / "missing.x3p")
    assert err.strip() == f"fvm: error: {raised.value}"


def test_find_calottes_on_a_generated_dimple():
    # A flat face with one spherical dimple of radius 1.5 mm, 0.2 mm deep (1.5 mm across), centred at (1.01, 0.93)
    # mm of a 2 x 1.8 mm map of 2 um pixels with 0.1 um height noise: the centre comes back within 4 of its
    # standard uncertainties (and within 0.2 um).
    rng = np.random.default_rng(2)
    dx, r, depth, cx, cy = 0.002, 1.5, 0.2, 1.01, 0.93
    y, x = np.mgrid[0:900, 0:1000] * dx
    cz = r - depth  # the sphere's centre above the face
    inside = (x - cx) ** 2 + (y - cy) ** 2 < r ** 2 - cz ** 2
    z = np.zeros_like(x)
    z[inside] = cz - np.sqrt(r ** 2 - (x[inside] - cx) ** 2 - (y[inside] - cy) ** 2)
    z += rng.normal(0, 1e-4, z.shape)
    found = fvm.find_calottes(fvm.Surface(z, spacing=dx))
    assert len(found["calottes"]) == 1
    c = found["calottes"][0]
    truth = np.array([cx, cy, cz])
    assert np.all(np.abs(c["centre"] - truth) < np.maximum(4 * c["u_centre"], 1e-6))
    assert np.all(np.abs(c["centre"] - truth) < 2e-4)
    assert c["radius"] == pytest.approx(r, abs=2e-4)
    with pytest.raises(fvm.InputError, match="no calotte found"):
        fvm.find_calottes(fvm.Surface(np.zeros((100, 100)) + rng.normal(0, 1e-4, (100, 100)), spacing=dx), name="flat.x3p")
