# Data no one on this project made (../shared/realdata, README there): NIST's certified fits and real instrument
# exports. Skipped where ../shared is absent (a user's clone).
import numpy as np
import pytest

import fvm
from conftest import REPO

REAL = REPO.parent / "shared" / "realdata"
pytestmark = pytest.mark.skipif(not REAL.is_dir(), reason=f"{REAL} is absent")


def nist_points(path):
    lines = path.read_text().split("\n")
    count = int(lines[0])
    return np.array([[float(v) for v in line.split()] for line in lines[1:1 + count]])


@pytest.mark.parametrize("n", [1, 4, 7, 13])  # the calotte-like caps of about 45 degrees
def test_sphere_fit_equals_nists_certified_sphere(n):
    fit = fvm.fit_sphere(nist_points(REAL / "spheres" / "nist-l2" / f"sph{n}.ds"))
    ref = [float(v) for v in (REAL / "spheres" / "nist-l2" / f"sph{n}.fit").read_text().split()]
    # NIST certifies its fits to all digits shown; shape_fit.h finishes in long double for the last digits of
    # double. 1e-9 mm on coordinates up to 1000 mm is 1e-12 relative: room for the solvers' stopping rules, and
    # a million times below what a fit that stopped short (or the algebraic start) is off by.
    np.testing.assert_allclose(fit.centre, ref[:3], rtol=0, atol=1e-9)
    assert abs(2 * fit.radius - ref[3]) < 1e-9


@pytest.mark.parametrize("n", [1, 2, 3])
def test_plane_fit_equals_nists_certified_plane(n):
    fit = fvm.fit_plane(nist_points(REAL / "planes" / "nist-l2" / f"pla{n}.ds"))
    ref = np.array([float(v) for v in (REAL / "planes" / "nist-l2" / f"pla{n}.fit").read_text().split()])
    np.testing.assert_allclose(fit.point, ref[:3], rtol=0, atol=1e-9)
    np.testing.assert_allclose(fit.normal * np.sign(fit.normal @ ref[3:]), ref[3:], rtol=0, atol=1e-12)


def test_real_x3p_reads_with_its_published_figures():
    s = fvm.read_surface(REAL / "surfaces" / "x3p-2.x3p")
    h = s.heights[s.mask]
    assert s.heights.shape == (650, 650) and s.mask.all()
    # The RMS height about the mean that an independent reader's tests assert (7.728033273597876e-8 m), to 1e-9
    # relative: the sum over 420k points in double.
    assert np.sqrt(np.mean((h - h.mean()) ** 2)) * 1e-3 == pytest.approx(7.728033273597876e-8, rel=1e-9)


def test_real_al3d_reads_with_its_pixel_size():
    s = fvm.read_surface(REAL / "surfaces" / "al3d-1.al3d")
    assert s.spacing == pytest.approx((4.38027e-4, 4.38027e-4), rel=1e-12)
    assert s.heights.shape == (296, 200)
    h = s.heights[s.mask]
    # The published RMS height (7.688266102603082e-6 m) is 3e-8 relative from ours, the float32 heights summed in
    # another precision; 1e-6 allows that and still fails a wrong unit, scale or a texture plane read as heights.
    assert np.sqrt(np.mean((h - h.mean()) ** 2)) * 1e-3 == pytest.approx(7.688266102603082e-6, rel=1e-6)
