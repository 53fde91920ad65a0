"""Surface optics of the improved ray tracing: Fresnel, Snell, absorption, Phong, Blinn.

All functions are vectorised over rays: directions and normals are (N, 3) arrays of unit
vectors, scalars broadcast.
"""

from __future__ import annotations

import math

import numpy as np


def dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row by row dot products of (N, 3) arrays.

    Summed as numpy's ``einsum("ij,ij->i")`` sums them, (0 + a0 b0 + a2 b2) + a1 b1, so every value
    is the same to the last bit (a sum of -0 terms is +0), in half its time: einsum loops over
    each row's three products on its own. (Rows not contiguous in memory einsum sums in order: those
    go to einsum itself.)"""
    if a.strides[-1] != 8 or b.strides[-1] != 8 or a.dtype != np.float64 or b.dtype != np.float64:
        return np.einsum("ij,ij->i", a, b)
    products = a * b
    out = products[:, 0] + products[:, 2]
    out += products[:, 1]
    out += 0.0
    return out


def scaled(v: np.ndarray, s: np.ndarray) -> np.ndarray:
    """``v * s[:, None]`` for (N, C) ``v`` (directions, or C colour channels): the same products a
    column at a time, in about half the time (numpy broadcasts slowly over short rows)."""
    out = np.empty(v.shape)
    for j in range(v.shape[1]):
        np.multiply(v[:, j], s, out=out[:, j])
    return out


def normalize(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` scaled to unit length (a single vector too).

    The quotients of ``v / length[:, None]``: numpy divides by a broadcast (N, 1) column an element
    at a time, but by a whole (N, 3) array with vector instructions, so each row's length is first
    copied into its three places (copies are exact)."""
    if v.ndim == 1:
        return v / np.sqrt(v @ v)
    length = dot(v, v)
    np.sqrt(length, out=length)
    if v.dtype != np.float64:
        return v / length[:, None]
    out = np.empty(v.shape)
    for j in range(v.shape[1]):
        out[:, j] = length
    return np.divide(v, out, out=out)


def fresnel_reflectance(cos_i: np.ndarray, n1: np.ndarray | float, n2: np.ndarray | float) -> np.ndarray:
    """Unpolarised reflectance R = (R_s + R_p) / 2 of the exact Fresnel equations (paper §3.3.1,
    ``fresnel_polarised``): ``cos_i`` the cosine of the angle of incidence (clipped to [0, 1]),
    ``n1`` the index on the incident side, ``n2`` on the far side. Total internal reflection gives
    exactly 1."""
    r_s, r_p = fresnel_polarised(np.clip(cos_i, 0.0, 1.0), n1, n2)
    return (r_s + r_p) * 0.5


def fresnel_polarised(cos_i: np.ndarray, n1: np.ndarray | float, n2: np.ndarray | float
                      ) -> tuple[np.ndarray, np.ndarray]:
    """The s- and p-polarised reflectances R_s = r_s², R_p = r_p² of the exact Fresnel equations
    (Born & Wolf, Principles of Optics, §1.5.2), broadcast over ``cos_i`` (>= 0) and the indices
    ``n1`` (incident side) and ``n2``; total internal reflection gives exactly 1 for both."""
    eta = n1 / n2
    sin2_t = (1.0 - cos_i * cos_i) * (eta * eta)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - sin2_t))
    r_s = _ratio(n1 * cos_i, n2 * cos_t)
    r_p = _ratio(n2 * cos_i, n1 * cos_t)
    tir = sin2_t >= 1.0
    return np.where(tir, 1.0, r_s * r_s), np.where(tir, 1.0, r_p * r_p)


def _ratio(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(a - b) / (a + b)."""
    return (a - b) / (a + b)


def reflect(d: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Mirror direction of ``d`` about the unit normal ``n`` (either orientation), of unit length.

    Renormalised: a ray may bounce dozens of times inside the lens (total internal reflection),
    and each bounce would otherwise multiply the rounding error of its length."""
    return normalize(d - scaled(n, dot(d, n) * 2.0))  # d - 2 (d·n) n


def refract(d: np.ndarray, n: np.ndarray, eta: np.ndarray | float, cos_i: np.ndarray | None = None) -> np.ndarray:
    """Snell's law. ``n`` faces the incident side (d·n < 0), ``eta`` = n1 / n2; ``cos_i`` is -d·n
    when the caller has it already.

    Only meaningful where there is no total internal reflection (callers mask those rays).
    """
    if cos_i is None:
        cos_i = -dot(d, n)
    eta = np.broadcast_to(eta, cos_i.shape)
    cos_t = np.sqrt(np.maximum(0.0, 1.0 - (1.0 - cos_i * cos_i) * (eta * eta)))
    # t = eta d + (eta cos i - cos t) n, of unit length as in reflect()
    return normalize(scaled(d, eta) + scaled(n, eta * cos_i - cos_t))


def absorption(coeff: np.ndarray, length: np.ndarray) -> np.ndarray:
    """Equation (2): the fraction of each channel left after ``length`` mm in the lens."""
    return np.exp(scaled(-coeff, length))


def phong(normal: np.ndarray, view: np.ndarray, light_dir: np.ndarray, diffuse: np.ndarray,
          light_color: np.ndarray, ambient: float, specular: np.ndarray | float,
          shininess: np.ndarray | float) -> np.ndarray:
    """Equation (1): [d + (1-d) cos θ] C0 + w (cos β)^n C1, cosines below 0 counted as 0, and
    no specular term where the light is behind the surface, cos θ <= 0 (docs/model.md §4).

    ``view`` points from the surface to the eye, ``light_dir`` from the surface to the light.
    ``diffuse`` is (N, 3) or (3,); returns (N, 3).
    """
    # Not ``normal @ light_dir``: a matrix product wakes BLAS's own threads, which spin on the
    # cores the tracer's bands run on.
    cos_theta = normal[:, 0] * light_dir[0] + normal[:, 1] * light_dir[1] + normal[:, 2] * light_dir[2]
    half = normalize(view + light_dir)
    cos_beta = np.maximum(0.0, dot(normal, half))
    diffuse_term = (ambient + (1.0 - ambient) * np.maximum(0.0, cos_theta))[:, None] * diffuse
    spec = np.where(cos_theta > 0.0, np.asarray(specular) * np.power(cos_beta, shininess), 0.0)
    return diffuse_term + spec[:, None] * light_color


def blinn(normal: np.ndarray, view: np.ndarray, to_light: np.ndarray, weight: np.ndarray,
          shininess: np.ndarray) -> np.ndarray:
    """Equation (3) without I0: w (cos β)^n with β between the normal and the half vector."""
    cos_beta = dot(normal, normalize(view + to_light))
    np.maximum(0.0, cos_beta, out=cos_beta)
    return weight * np.power(cos_beta, shininess)


# Directions for light leaving a surface or a point (the forward light tracing of the measures, on the
# parametric parts and on meshes)

def cosine_directions(normal: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Unit directions (N, 3) distributed as cos θ about unit ``normal`` (N, 3): the normal plus a
    uniform point of the unit sphere, normalised (a point uniform on the sphere tangent to the
    surface projects to a cosine-distributed direction)."""
    while True:
        d = normal + uniform_sphere(len(normal), rng)
        length = np.linalg.norm(d, axis=1)
        if np.all(length > 1e-9):
            return d / length[:, None]


def uniform_sphere(n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` unit vectors uniform on the sphere (Archimedes: z uniform in [−1, 1])."""
    z = rng.uniform(-1.0, 1.0, n)
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    s = np.sqrt(1.0 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)
