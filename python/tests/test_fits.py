# Sphere and plane fits of points generated here from a known shape with seeded noise.
import numpy as np
import pytest

import fvm


def sphere_cap(rng, centre, radius, n, noise_mm):
    """n points on the upper half of a sphere, each moved along its normal by Gaussian noise."""
    theta = np.arccos(rng.uniform(0.0, 1.0, n))  # polar angle from +z: the cap a probe reaches
    phi = rng.uniform(0.0, 2 * np.pi, n)
    normals = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], axis=1)
    return np.asarray(centre) + normals * (radius + rng.normal(0.0, noise_mm, n))[:, None]


def test_sphere_fit_recovers_the_known_sphere_within_its_uncertainty():
    rng = np.random.default_rng(20261124)
    centre, radius, noise = np.array([12.5, -3.25, 40.0]), 12.7, 0.001  # a 25.4 mm ball, 1 um probing noise
    fit = fvm.fit_sphere(sphere_cap(rng, centre, radius, 400, noise))
    # The fit's own standard uncertainties (from its residuals) must cover the truth: 4 u is a 6e-5 chance per
    # coordinate under Gaussian noise, so a failure means a wrong fit or a wrong uncertainty, not bad luck.
    assert fit.has_uncertainty
    assert np.all(np.abs(fit.centre - centre) < 4 * fit.u_centre)
    assert abs(fit.radius - radius) < 4 * fit.u_radius
    # And the uncertainties are what 1 um noise over 400 points of a hemisphere gives: about sigma / sqrt(N / 3)
    # per coordinate (0.09 um); between a third and three times that says they are not off by a unit or a square.
    assert 0.03e-3 < fit.u_radius < 0.3e-3
    assert fit.rms == pytest.approx(noise, rel=0.15)  # the residual RMS estimates the noise (400 samples: ~4 %)


def test_robust_sphere_fit_leaves_out_stray_points():
    rng = np.random.default_rng(7)
    points = sphere_cap(rng, [0, 0, 0], 5.0, 300, 0.0005)
    points[:30] += rng.uniform(0.05, 0.5, (30, 3))  # 10 % mixed pixels, 50-500 um off the surface
    fit = fvm.fit_sphere(points, robust=True)
    assert not fit.inlier[:30].any()  # every stray point is at least 100 noise sigmas out
    assert fit.outliers >= 30
    assert abs(fit.radius - 5.0) < 4 * fit.u_radius


def test_plane_fit_recovers_the_known_normal():
    rng = np.random.default_rng(3)
    normal = np.array([0.01, -0.02, 1.0]) / np.linalg.norm([0.01, -0.02, 1.0])
    u_axis = np.cross(normal, [1.0, 0.0, 0.0])
    u_axis /= np.linalg.norm(u_axis)
    v_axis = np.cross(normal, u_axis)
    s, t = rng.uniform(-10, 10, (2, 500))  # a 20 mm square flat
    points = np.array([1.0, 2.0, 3.0]) + np.outer(s, u_axis) + np.outer(t, v_axis) + np.outer(rng.normal(0, 0.002, 500), normal)
    fit = fvm.fit_plane(points)
    angle = np.arccos(min(1.0, abs(float(fit.normal @ normal))))
    # The tilt error is within 4 of the fit's own standard uncertainties (u_normal_rad is the larger principal one).
    assert angle < 4 * fit.u_normal_rad
    # Computed independently: a line fit's slope has u = sigma / sqrt(N var(s)), var of a uniform 20 mm span
    # 400 / 12 mm^2, so 2 um over 500 points gives 15.5 urad; the fit's own figure (from its residuals, ~3 %
    # off with 500 points, and the larger of two tilts) lies within 30 % of it.
    predicted = 0.002 / np.sqrt(500 * 400 / 12)
    assert 0.7 * predicted < fit.u_normal_rad < 1.3 * predicted
    assert abs(float((fit.point - [1.0, 2.0, 3.0]) @ normal)) < 4 * 0.002 / np.sqrt(500)


def test_fits_refuse_what_cannot_determine_the_shape():
    with pytest.raises(fvm.InputError):
        fvm.fit_sphere(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 2, 0.0]]))  # coplanar
    with pytest.raises(fvm.InputError, match="N x 3"):
        fvm.fit_plane(np.zeros((5, 2)))
    with pytest.raises(fvm.InputError, match="not finite"):
        fvm.fit_plane(np.array([[0, 0, 0], [1, 0, 0], [0, 1, np.nan]]))
    assert issubclass(fvm.InputError, ValueError)
