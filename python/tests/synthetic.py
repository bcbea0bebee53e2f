# Synthetic images for the tests, generated with numpy from a fixed seed: a random texture and its Gaussian blur.
import numpy as np


def gaussian_blur(image, sigma_px):
    """Periodic Gaussian blur through the FFT (exact for a Gaussian: the transform of the kernel is Gaussian)."""
    fy = np.fft.fftfreq(image.shape[0])[:, None]
    fx = np.fft.fftfreq(image.shape[1])[None, :]
    kernel = np.exp(-2 * np.pi ** 2 * sigma_px ** 2 * (fx ** 2 + fy ** 2))
    return np.real(np.fft.ifft2(np.fft.fft2(image) * kernel))


def texture(rng, rows, cols, grain_px=1.0):
    """Random texture of unit contrast, correlated over about grain_px, around a mid-grey of 0.5."""
    t = gaussian_blur(rng.normal(size=(rows, cols)), grain_px)
    return 0.5 + 0.15 * t / t.std()
