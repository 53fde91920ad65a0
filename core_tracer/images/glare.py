"""Glare: the eye's scatter of the brightest pixels, applied to the linear image.

The paper finds the brilliance of the light source not rendered well enough (§5(1)). A lit bulb
looks brilliant to the eye because the eye's optics scatter part of its light over the retina
around it. This module adds that scatter with the point-spread function (PSF) of Spencer,
Shirley, Zimmerman and Greenberg, "Physically-Based Glare Effects for Digital Images"
(SIGGRAPH 1995), for an eye adapted to daylight (photopic):

    P(θ) = 0.384 f0(θ) + 0.478 f1(θ) + 0.138 f2(θ),   θ in degrees of visual angle
    f0(θ) = 2.61e6 exp(-(θ / 0.02)²)     the eye's sharp core
    f1(θ) = 20.91 / (θ + 0.02)³          near scatter (bloom)
    f2(θ) = 72.37 / (θ + 0.02)²          far scatter, the veiling glow (bloom)

Not implemented: the paper's flare (the ciliary corona's radial streaks and the lenticular
halo's coloured ring, f3), and its scotopic and mesopic weights (an eye adapted to the dark).
The PSF is the same for every channel (no wavelength dependence).

How it is applied, per channel:

- Only the light above ``glare.threshold`` (a linear level; 1 is display white at 0 EV in
  Standard) spreads, and of it the fraction ``glare.strength``; the rest of every pixel stays
  where it is. An image with no pixel above the threshold comes back unchanged, bit for bit.
- The PSF is integrated over each pixel (the core f0 exactly, by erf; f1 and f2 by supersampling
  the pixels near the centre), truncated at the largest offset two pixels of the image can have,
  and normalised to sum 1.
- Energy is conserved: the PSF of each source pixel is renormalised over the frame, so light
  that would scatter out of the image stays in it, and each channel's total is unchanged (to
  float rounding).
- A pixel spans the visual angle of the camera's central pixel: ``fov_deg`` over the fitted side
  (an orthographic camera is taken as seen over ``fov_deg`` as well).

Cost: three real FFTs of size about (2H) x (2W) per channel, plus two for the PSF and the frame
weights; float64 throughout, about ``BYTES_PER_PIXEL`` bytes per image pixel at the peak
(``budget`` counts it).
"""

from __future__ import annotations

import math

import numpy as np

from .. import budget

# Spencer et al. 1995, photopic PSF: weights of f0, f1, f2.
PHOTOPIC = (0.384, 0.478, 0.138)
F0_PEAK, F0_WIDTH_DEG = 2.61e6, 0.02
F1_SCALE, F2_SCALE, OFFSET_DEG = 20.91, 72.37, 0.02
# f1 and f2 are supersampled in the pixels within this many pixels of the centre, finely enough to
# resolve their 0.02 degree knee (at most MAX_SUBSAMPLES per pixel side).
NEAR_PIXELS = 2
SUBSAMPLE_DEG = 0.004
MAX_SUBSAMPLES = 256
# Peak bytes per image pixel: a few float64/complex128 arrays of the padded (2H x 2W) size.
BYTES_PER_PIXEL = budget.GLARE_BYTES_PER_PIXEL


def scatter(theta_deg: np.ndarray) -> np.ndarray:
    """The bloom terms of the photopic PSF, 0.478 f1 + 0.138 f2, per square degree."""
    t = np.asarray(theta_deg, dtype=np.float64) + OFFSET_DEG
    return PHOTOPIC[1] * F1_SCALE / t**3 + PHOTOPIC[2] * F2_SCALE / t**2


def psf(theta_deg: np.ndarray) -> np.ndarray:
    """The photopic PSF P(θ) of Spencer et al. (unnormalised, per square degree)."""
    theta = np.asarray(theta_deg, dtype=np.float64)
    return PHOTOPIC[0] * F0_PEAK * np.exp(-(theta / F0_WIDTH_DEG) ** 2) + scatter(theta)


def _core_1d(offsets: np.ndarray, deg_per_px: float) -> np.ndarray:
    """∫ exp(-(x/w)²) dx over the pixels at ``offsets``, x in degrees (f0 is separable in x and y)."""
    edges = (np.arange(offsets[0], offsets[-1] + 2) - 0.5) * deg_per_px / F0_WIDTH_DEG
    erf = np.array([math.erf(e) for e in edges])
    return np.diff(erf) * (F0_WIDTH_DEG * math.sqrt(math.pi) / 2.0)


def kernel(height: int, width: int, deg_per_px: float) -> np.ndarray:
    """The PSF integrated over pixels, for offsets -(H-1)..H-1 by -(W-1)..W-1 (centre in the
    middle), normalised to sum 1. float64, shape (2H-1, 2W-1)."""
    dy = np.arange(-(height - 1), height)
    dx = np.arange(-(width - 1), width)
    area = deg_per_px * deg_per_px
    r = np.hypot(dy[:, None], dx[None, :]) * deg_per_px
    k = scatter(r) * area  # pixel-centre value times pixel area: f1 and f2 are smooth away from 0
    n = max(1, min(MAX_SUBSAMPLES, math.ceil(deg_per_px / SUBSAMPLE_DEG)))
    sub = (np.arange(n) + 0.5) / n - 0.5
    cy, cx = height - 1, width - 1
    for oy in range(-min(NEAR_PIXELS, height - 1), min(NEAR_PIXELS, height - 1) + 1):
        for ox in range(-min(NEAR_PIXELS, width - 1), min(NEAR_PIXELS, width - 1) + 1):
            rr = np.hypot(oy + sub[:, None], ox + sub[None, :]) * deg_per_px
            k[cy + oy, cx + ox] = scatter(rr).mean() * area
    k += PHOTOPIC[0] * F0_PEAK * np.outer(_core_1d(dy, deg_per_px), _core_1d(dx, deg_per_px))
    return k / k.sum()


def degrees_per_pixel(camera: dict, width: int, height: int) -> float:
    """The visual angle of the central pixel, in degrees, for the scene's camera."""
    fit = camera["sensor_fit"]
    if fit == "auto":
        fit = "horizontal" if width >= height else "vertical"
    side = width if fit == "horizontal" else height
    half_tan = math.tan(math.radians(camera["fov_deg"]) / 2.0)
    return math.degrees(2.0 * math.atan(half_tan / side))


def _fast_size(n: int) -> int:
    """The smallest m >= n whose only prime factors are 2, 3 and 5 (fast for numpy's FFT)."""
    m = n
    while True:
        k = m
        for p in (2, 3, 5):
            while k % p == 0:
                k //= p
        if k == 1:
            return m
        m += 1


def spread(image: np.ndarray, threshold: float, strength: float, deg_per_px: float) -> np.ndarray:
    """Glare of ``image`` (H, W, 3 linear): the light above ``threshold``, times ``strength``,
    spread by the normalised PSF, energy-conserving per channel. Returns ``image`` itself when no
    light spreads; otherwise a new float32 array."""
    excess = np.maximum(image.astype(np.float64) - threshold, 0.0) * strength
    if not excess.any():
        return image
    h, w = image.shape[:2]
    fh, fw = _fast_size(2 * h - 1), _fast_size(2 * w - 1)
    # Circular convolution of size >= 2H-1 x 2W-1 with the kernel's offsets placed modulo the size
    # is the linear convolution on the frame: offsets between two pixels never wrap onto each other.
    k = np.zeros((fh, fw))
    small = kernel(h, w, deg_per_px)
    k[np.ix_(np.arange(-(h - 1), h) % fh, np.arange(-(w - 1), w) % fw)] = small
    del small
    k_hat = np.fft.rfft2(k)
    del k

    def convolve(a: np.ndarray) -> np.ndarray:
        return np.fft.irfft2(np.fft.rfft2(a, s=(fh, fw)) * k_hat, s=(fh, fw))[:h, :w]

    # The share of each source pixel's PSF that lands in the frame (the PSF is symmetric, so this
    # is the frame convolved with it); dividing by it keeps the light that would leave the image.
    inside = convolve(np.ones((h, w)))
    out = image.astype(np.float64) - excess
    for c in range(image.shape[2]):
        if excess[..., c].any():
            out[..., c] += convolve(excess[..., c] / inside)
    # FFT rounding (about 1e-16 of the spread light) must not make a dark pixel negative.
    return np.maximum(out, 0.0).astype(np.float32)


def apply(image: np.ndarray, scene: dict) -> np.ndarray:
    """The scene's glare on its rendered linear image (H, W, 3); ``image`` itself when glare is off.

    The one function the CLI (render, study) and Blender (the engine's F12 result, the add-on's
    Lamp Tracer image) call, so they show the same pixels."""
    glare = scene.get("glare")
    if not glare or not glare["on"]:
        return image
    h, w = image.shape[:2]
    return spread(image, glare["threshold"], glare["strength"], degrees_per_pixel(scene["camera"], w, h))
