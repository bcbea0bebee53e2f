# A focus stack generated here with a known surface, reconstructed by fvm.focus.
import numpy as np

import fvm
from synthetic import gaussian_blur, texture


def test_focus_stack_round_trip_recovers_two_known_heights():
    # A textured part with two flat levels, 10.3 and 25.1 um, imaged at z = 0, 2, ..., 36 um. Each image is the
    # texture blurred by a Gaussian whose variance grows as a parabola in the defocus, s^2 = s0^2 + (k dz)^2
    # (s0 0.7 px, k 0.5 px per um), the model the power peak fit inverts; 0.3 % image noise.
    rng = np.random.default_rng(42)
    rows, cols, step = 64, 128, 0.002
    levels = (0.0103, 0.0251)
    truth = np.where(np.arange(cols)[None, :] < cols // 2, levels[0], levels[1]) * np.ones((rows, 1))
    sharp = texture(rng, rows, cols, grain_px=2.0)
    z = np.arange(19) * step
    stack = np.empty((len(z), rows, cols), dtype=np.float32)
    for i, zi in enumerate(z):
        for level in levels:
            sigma = np.hypot(0.7, 500.0 * (zi - level))
            stack[i][truth == level] = gaussian_blur(sharp, sigma)[truth == level]
        stack[i] += rng.normal(0, 0.003, (rows, cols)).astype(np.float32)
    r = fvm.focus(stack, z, dx_mm=0.001)
    assert r["heights"].shape == (rows, cols) and r["spacing"] == (0.001, 0.001)
    for level, columns in zip(levels, (slice(8, 56), slice(72, 120))):
        h = r["heights"][8:56, columns]  # away from the step (the window mixes both levels there) and the border
        valid = h[np.isfinite(h)]
        assert valid.size > 0.8 * h.size  # the rest lacks a clear enough peak (quality below 2)
        # Single pixels scatter by ~65 nm here, so the median of ~2000 of them has a standard error of ~2 nm: 20 nm
        # (1 % of a step) is ~8 of those, and a peak fit that snapped to images or leaned towards one fails it.
        assert abs(np.median(valid) - level) < 0.02e-3
        # Each pixel's uncertainty says how far its height scatters: u less its floor of 0.5 % of the step (the
        # interpolation between images on stacks the model does not fit exactly; this stack is the model itself)
        # within a factor 2 of the spread (1.4826 MAD, robust to the few wild pixels) the flat level shows: 44-54 nm
        # against 31 nm (u also holds the heights' roughness at the window's scale, which the MAD of single pixels
        # counts only in part).
        spread = 1.4826 * np.median(np.abs(valid - np.median(valid)))
        u = r["u"][8:56, columns]
        u_scatter = np.sqrt(np.maximum(u * u - (0.005 * step) ** 2, 0.0))
        assert 0.5 * spread < np.nanmedian(u_scatter) < 2 * spread
        assert np.nanmedian(u) >= 0.005 * step
    # Two faces each level within a step show the peak fit's phase bias at two phases only: none is taken off, and
    # the summary says why.
    assert r["summary"]["phase_bias_rms"] is None and "phases" in r["summary"]["phase_bias_declined"]
    # The blur grows in quadrature from its floor: the focus curve has a round top (shape ratio 4.39, 4 for a
    # parabola), so the steep walls' bias, which only V-topped curves show, is not taken off.
    assert r["summary"]["focus_curve"]["shape_ratio"] > 3.5 and r["summary"]["steep_wall_bias_share"] == 0.0
    # The all-in-focus image is the sharp texture: correlation near 1 (the noise and the s0 blur keep it below).
    inner = np.s_[8:56, 8:120]
    assert np.corrcoef(r["image"][inner].ravel(), sharp[inner].ravel())[0, 1] > 0.95


def test_focus_refuses_unsorted_z():
    stack = np.zeros((4, 16, 16), dtype=np.uint8)
    try:
        fvm.focus(stack, [0.0, 0.002, 0.001, 0.003])
    except fvm.InputError as e:
        assert "z" in str(e)
    else:
        raise AssertionError("unsorted z was accepted")
