# A focus stack generated here with a known surface, reconstructed by fvm.focus.
import numpy as np

import fvm
from synthetic import gaussian_blur, texture


def test_focus_stack_round_trip_recovers_two_known_heights():
    # A textured part with two flat levels, 10.3 and 25.1 um, imaged at z = 0, 2, ..., 36 um. Each image is the
    # texture blurred by a Gaussian whose variance grows as a parabola in the defocus, s^2 = s0^2 + (k dz)^2
    # (s0 0.7 px, k 1 px per um), the model the power peak fit inverts exactly; 1 % image noise.
    rng = np.random.default_rng(42)
    rows, cols, step = 64, 128, 0.002
    truth = np.where(np.arange(cols)[None, :] < cols // 2, 0.0103, 0.0251) * np.ones((rows, 1))
    sharp = texture(rng, rows, cols)
    z = np.arange(19) * step
    stack = np.empty((len(z), rows, cols), dtype=np.float32)
    for i, zi in enumerate(z):
        for level in (0.0103, 0.0251):
            sigma = np.hypot(0.7, 1000.0 * (zi - level))
            stack[i][truth == level] = gaussian_blur(sharp, sigma)[truth == level]
        stack[i] += rng.normal(0, 0.01, (rows, cols)).astype(np.float32)
    r = fvm.focus(stack, z, dx_mm=0.001)
    assert r["heights"].shape == (rows, cols) and r["spacing"] == (0.001, 0.001)
    # Away from the step (the window mixes both levels there) and the border: the medians over ~1500 pixels each
    # within 0.1 step (0.2 um) of the truth. What is left is the noise of single pixels (their u, about 0.1 um)
    # averaged down, so the bound is loose by an order of magnitude, yet a peak fit that snapped to images, or
    # a half-step bias, fails it.
    for level, columns in ((0.0103, slice(8, 56)), (0.0251, slice(72, 120))):
        h = r["heights"][8:56, columns]
        assert np.isfinite(h).mean() > 0.95
        assert abs(np.nanmedian(h) - level) < 0.1 * step
        u = r["u"][8:56, columns]
        assert 0 < np.nanmedian(u) < 0.5 * step  # a per-pixel uncertainty well inside a step
    # The all-in-focus image is the sharp texture: correlation near 1 (the noise and the s0 blur keep it below).
    inner = np.s_[8:56, 8:120]
    assert np.corrcoef(r["image"][inner].ravel(), sharp[inner].ravel())[0, 1] > 0.9


def test_focus_refuses_unsorted_z():
    stack = np.zeros((4, 16, 16), dtype=np.uint8)
    try:
        fvm.focus(stack, [0.0, 0.002, 0.001, 0.003])
    except fvm.InputError as e:
        assert "z" in str(e)
    else:
        raise AssertionError("unsorted z was accepted")
