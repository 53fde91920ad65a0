"""An LED's far-field intensity from its supplier's file, and the die luminance that gives it.

Files (type C photometry, CIE 121: γ the angle from the light's axis, C the azimuth about it):
- IES LM-63 (IESNA LM-63-2002, and the 1995 and 2019 texts, which keep the numbers' layout):
  keyword lines up to ``TILT=``, then the lamps, lumens per lamp, candela multiplier, numbers of
  vertical and horizontal angles, photometric type (1 = C), units, the opening's size, ballast
  factor, file generation type, input watts, the vertical angles, the horizontal angles and the
  candela values, one horizontal angle after another. ``TILT=NONE`` only (a tilt table is for
  lamps whose output changes with the luminaire's tilt, not for an LED).
- EULUMDAT (Stockmar, LiTG 1990): 26 header lines (line 3 the symmetry, 4–7 the numbers and steps of
  C planes and γ angles, 26 the number of lamp sets n, then 6 n lines about them), 10 direct ratios,
  the C angles, the γ angles and the intensities in cd/klm, for the planes the symmetry keeps.
The symmetric files are unfolded to the whole circle of C (IES: last horizontal angle 0, 90 or
180; EULUMDAT: symmetry 1–4).

A flat die of area A whose luminance is L(θ, φ) sends, seen from far, I(θ, φ) = L(θ, φ) A cos θ; so
the luminance that gives the file's intensity shape is L = I / (A cos θ) (the near field a far-field
file implies, docs/photometric.md: wrong for an eye closer than about ten die sizes). Only the shape
is used: I is scaled so that the die emits its stated flux Φ into its half space, Φ = ∫ I dΩ over
θ < 90°. The engine takes L relative to a Lambertian die of the same flux (L_0 = Φ / (π A)):

    f(θ, φ) = L / L_0 = π I_file(θ, φ) / (Φ_file cos θ),   Φ_file = ∫_{θ<90°} I_file dΩ,

tabulated on a regular (θ, φ) grid (``Pattern``), 1 everywhere for a Lambertian die. Light in the
file behind the die's plane (γ > 90°) cannot leave a flat die's front and is left out.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

FILE_MAX_BYTES = 2_000_000
THETA_STEP_DEG = 0.5
PHI_STEP_DEG = 1.0
MIN_COS = math.cos(math.radians(89.75))  # f's cos θ near the die's plane, where I / cos θ has no limit


class FarFieldError(ValueError):
    """A far-field file that cannot be used; ``str()`` is the one-line message naming the file."""


@dataclass(frozen=True)
class FarField:
    """Intensities ``cd[i, j]`` (any unit: only the shape is used) at C = ``c_deg[i]`` (0 to 360
    inclusive, the full circle) and γ = ``gamma_deg[j]`` (increasing, within 0–180)."""

    c_deg: np.ndarray
    gamma_deg: np.ndarray
    cd: np.ndarray
    name: str = ""

    def at(self, c_deg: np.ndarray, gamma_deg: np.ndarray) -> np.ndarray:
        """Bilinear in (C, γ) (as ``measures.export.Distribution.at``), C periodic; 0 outside the
        file's γ range. ``c_deg`` and ``gamma_deg`` broadcast together."""
        c, g = np.broadcast_arrays(np.mod(np.asarray(c_deg, float), 360.0), np.asarray(gamma_deg, float))
        i = np.clip(np.searchsorted(self.c_deg, c, side="right") - 1, 0, len(self.c_deg) - 2)
        tc = (c - self.c_deg[i]) / (self.c_deg[i + 1] - self.c_deg[i])
        j = np.clip(np.searchsorted(self.gamma_deg, g, side="right") - 1, 0, max(len(self.gamma_deg) - 2, 0))
        if len(self.gamma_deg) == 1:
            tg = np.zeros_like(g)
            j1 = j
        else:
            tg = np.clip((g - self.gamma_deg[j]) / (self.gamma_deg[j + 1] - self.gamma_deg[j]), 0.0, 1.0)
            j1 = j + 1
        row0 = (1 - tg) * self.cd[i, j] + tg * self.cd[i, j1]
        row1 = (1 - tg) * self.cd[i + 1, j] + tg * self.cd[i + 1, j1]
        out = (1 - tc) * row0 + tc * row1
        outside = (g < self.gamma_deg[0] - 1e-9) | (g > self.gamma_deg[-1] + 1e-9)
        return np.where(outside, 0.0, out)


def _fail(shown: str, message: str) -> FarFieldError:
    return FarFieldError(f"{shown}: {message}")


def _text_of(path: str | os.PathLike) -> tuple[str, str]:
    name = os.fspath(path)
    shown = os.path.basename(name) or name
    try:
        size = os.path.getsize(name)
        if size > FILE_MAX_BYTES:
            raise _fail(shown, f"file is {size} bytes; allowed at most {FILE_MAX_BYTES} bytes")
        with open(name, "rb") as f:
            raw = f.read(FILE_MAX_BYTES + 1)
    except OSError as e:
        raise _fail(shown, f"cannot read the far-field file ({e.strerror or e})") from None
    return raw.decode("latin-1"), shown  # both formats are ASCII; latin-1 never fails on a stray byte


def _numbers(tokens: list[str], shown: str, what: str) -> list[float]:
    try:
        values = [float(t.replace(",", ".")) for t in tokens]
    except ValueError:
        raise _fail(shown, f"{what}: expected numbers") from None
    if not all(math.isfinite(v) for v in values):
        raise _fail(shown, f"{what}: values must be finite numbers")
    return values


def _full_circle(c: list[float], cd: np.ndarray, shown: str) -> tuple[np.ndarray, np.ndarray]:
    """The planes unfolded by symmetry to C from 0 to 360 inclusive (IES type C's rules: one plane
    is rotationally symmetric; planes up to 90° mirror into four quadrants, up to 180° into two)."""
    c_arr = np.asarray(c, dtype=np.float64)
    if np.any(np.diff(c_arr) <= 0):
        raise _fail(shown, "the C angles (horizontal angles) must increase")
    if len(c_arr) == 1:
        return np.array([0.0, 360.0]), np.vstack([cd, cd])
    first, last = c_arr[0], c_arr[-1]
    if first != 0.0:
        raise _fail(shown, f"the C angles start at {first:g}; allowed 0")
    if last == 90.0:
        c_arr, cd = np.concatenate([c_arr, 180.0 - c_arr[::-1][1:]]), np.vstack([cd, cd[::-1][1:]])
        last = 180.0
    if last == 180.0:
        c_arr, cd = np.concatenate([c_arr, 360.0 - c_arr[::-1][1:]]), np.vstack([cd, cd[::-1][1:]])
        last = 360.0
    if last < 360.0:  # the full circle given without its 360° plane: it is the 0° plane
        if last <= 180.0:
            raise _fail(shown, f"the C angles end at {last:g}; allowed 0, 90, 180 or a full circle")
        c_arr, cd = np.append(c_arr, 360.0), np.vstack([cd, cd[:1]])
    elif last > 360.0:
        raise _fail(shown, f"the C angles end at {last:g}; allowed at most 360")
    return c_arr, cd


def read_ies(path: str | os.PathLike) -> FarField:
    """An IES LM-63 file's type C intensities (candela multiplier and ballast factor applied)."""
    text, shown = _text_of(path)
    lines = text.splitlines()
    for at, line in enumerate(lines):
        if line.strip().upper().startswith("TILT"):
            tilt = line.split("=", 1)[1].strip().upper() if "=" in line else ""
            if tilt != "NONE":
                raise _fail(shown, f"TILT={tilt or '?'}; allowed TILT=NONE (an LED's far field has no tilt table)")
            tokens = " ".join(lines[at + 1:]).replace(",", " ").split()
            break
    else:
        raise _fail(shown, "no TILT= line; allowed an IES LM-63 file")
    if len(tokens) < 13:
        raise _fail(shown, "ends before its photometric numbers")
    head = _numbers(tokens[:13], shown, "the numbers after TILT")
    multiplier, n_vert, n_horiz, kind = head[2], int(head[3]), int(head[4]), int(head[5])
    ballast = head[10]
    if kind != 1:
        raise _fail(shown, f"photometric type {kind}; allowed 1 (type C, as LED data are given)")
    if not (1 <= n_vert <= 2000 and 1 <= n_horiz <= 2000):
        raise _fail(shown, f"{n_vert} vertical and {n_horiz} horizontal angles; allowed 1 to 2000 of each")
    need = 13 + n_vert + n_horiz + n_vert * n_horiz
    if len(tokens) < need:
        raise _fail(shown, f"has {len(tokens) - 13} values after its header; expected {need - 13}")
    values = _numbers(tokens[13:need], shown, "angles and candela values")
    gamma = np.asarray(values[:n_vert])
    c = values[n_vert:n_vert + n_horiz]
    cd = np.asarray(values[n_vert + n_horiz:]).reshape(n_horiz, n_vert) * multiplier * (ballast or 1.0)
    return _checked(shown, c, gamma, cd)


def read_ldt(path: str | os.PathLike) -> FarField:
    """A EULUMDAT file's intensities (cd/klm)."""
    text, shown = _text_of(path)
    lines = [line.strip() for line in text.splitlines()]
    if len(lines) < 26:
        raise _fail(shown, "ends before its 26 header lines; allowed a EULUMDAT file")
    head = _numbers([lines[2], lines[3], lines[4], lines[5], lines[6]], shown, "lines 3 to 7")
    symmetry, n_c, n_g = int(head[0]), int(head[1]), int(head[3])
    if symmetry not in range(5):
        raise _fail(shown, f"symmetry {symmetry}; allowed 0 to 4")
    if not (1 <= n_c <= 2000 and 1 <= n_g <= 2000):
        raise _fail(shown, f"{n_c} C planes and {n_g} gamma angles; allowed 1 to 2000 of each")
    sets = int(_numbers([lines[25]], shown, "line 26 (lamp sets)")[0])
    if not 1 <= sets <= 20:
        raise _fail(shown, f"{sets} lamp sets on line 26; allowed 1 to 20")
    at = 26 + 6 * sets + 10  # past the lamp sets and the 10 direct ratios
    tokens = " ".join(lines[at:]).split()
    kept = {0: n_c, 1: 1, 2: n_c // 2 + 1, 3: n_c // 2 + 1, 4: n_c // 4 + 1}[symmetry]
    if len(tokens) < n_c + n_g + kept * n_g:
        raise _fail(shown, f"has {len(tokens)} values after its header; expected {n_c + n_g + kept * n_g}")
    values = _numbers(tokens[:n_c + n_g + kept * n_g], shown, "angles and intensities")
    c_all, gamma = values[:n_c], np.asarray(values[n_c:n_c + n_g])
    cd = np.asarray(values[n_c + n_g:]).reshape(kept, n_g)
    if symmetry == 0:
        return _checked(shown, c_all, gamma, cd)
    # unfolded onto every C plane of the file: the kept plane each one mirrors (EULUMDAT's symmetries:
    # 1 about the axis, 2 about the C0-C180 plane, 3 about C90-C270, 4 about both)
    first = {1: 0, 2: 0, 3: n_c // 4, 4: 0}[symmetry]
    kept_c = np.asarray(c_all[first:first + kept]) if symmetry != 1 else np.zeros(1)
    full = np.zeros((n_c, n_g))
    for i, c in enumerate(c_all):
        image = {1: 0.0, 2: c if c <= 180.0 else 360.0 - c, 3: (180.0 - c) % 360.0 if (c < 90.0 or c > 270.0) else c,
                 4: min(c % 180.0, 180.0 - c % 180.0) if c % 180.0 else 0.0}[symmetry]
        match = np.nonzero(np.isclose(kept_c, image, atol=1e-6))[0]
        if not len(match):
            raise _fail(shown, f"no intensities for the C plane {c:g} by its symmetry {symmetry}")
        full[i] = cd[match[0]]
    return _checked(shown, c_all, gamma, full)


def _checked(shown: str, c: list[float], gamma: np.ndarray, cd: np.ndarray) -> FarField:
    if np.any(np.diff(gamma) <= 0) or gamma[0] < 0 or gamma[-1] > 180:
        raise _fail(shown, "the gamma (vertical) angles must increase within 0 to 180")
    if np.any(cd < 0):
        raise _fail(shown, "holds a negative intensity; allowed 0 or more")
    c_full, cd_full = _full_circle(c, cd, shown)
    return FarField(c_full, gamma, cd_full, shown)


def read_far_field(path: str | os.PathLike) -> FarField:
    """An .ies or .ldt file by its suffix."""
    name = os.fspath(path).lower()
    if name.endswith(".ies"):
        return read_ies(path)
    if name.endswith(".ldt"):
        return read_ldt(path)
    raise _fail(os.path.basename(os.fspath(path)), "allowed an .ies or .ldt file")


@dataclass(frozen=True)
class Pattern:
    """A die's luminance relative to a Lambertian die of the same flux, f(θ, φ) (module docstring),
    on the grid θ = 0, ``THETA_STEP_DEG`` … 90°, φ = 0, ``PHI_STEP_DEG`` … 360° (φ from the array's
    across direction toward its up direction, the file's C)."""

    table: np.ndarray  # (thetas, phis)

    @classmethod
    def lambertian(cls) -> Pattern:
        return cls(np.ones((1, 1)))

    @classmethod
    def of(cls, far: FarField) -> Pattern:
        theta = np.arange(0.0, 90.0 + 1e-9, THETA_STEP_DEG)
        phi = np.arange(0.0, 360.0 + 1e-9, PHI_STEP_DEG)
        intensity = far.at(phi[None, :], theta[:, None])  # (thetas, phis)
        intensity[-1] = 0.0  # light in the die's own plane (θ = 90°) does not leave a flat die
        flux = front_flux(theta, phi, intensity)
        if not flux > 0:
            raise FarFieldError(f"{far.name}: no light in front of the die (gamma below 90 degrees); allowed a file "
                                "whose axis, gamma 0, is the LED's")
        cos_t = np.maximum(np.cos(np.radians(theta)), MIN_COS)
        return cls(math.pi * intensity / (flux * cos_t[:, None]))

    def factor(self, cos_theta: np.ndarray, phi_deg: np.ndarray) -> np.ndarray:
        """f at the directions of (cos θ, φ in degrees); 0 behind the die (cos θ ≤ 0)."""
        if self.table.shape == (1, 1):
            return np.where(cos_theta > 0.0, 1.0, 0.0)
        theta = np.degrees(np.arccos(np.clip(cos_theta, -1.0, 1.0))) / THETA_STEP_DEG
        phi = np.mod(phi_deg, 360.0) / PHI_STEP_DEG
        i = np.clip(theta.astype(np.intp), 0, self.table.shape[0] - 2)
        j = np.clip(phi.astype(np.intp), 0, self.table.shape[1] - 2)
        ti, tj = np.clip(theta - i, 0.0, 1.0), np.clip(phi - j, 0.0, 1.0)
        t = self.table
        value = ((1 - ti) * ((1 - tj) * t[i, j] + tj * t[i, j + 1])
                 + ti * ((1 - tj) * t[i + 1, j] + tj * t[i + 1, j + 1]))
        return np.where(cos_theta > 0.0, value, 0.0)


def front_flux(theta_deg: np.ndarray, phi_deg: np.ndarray, intensity: np.ndarray) -> float:
    """∫∫ I sin θ dθ dφ over the grid (trapezoids in θ and φ), in the file's units × sr."""
    t, p = np.radians(theta_deg), np.radians(phi_deg)
    over_phi = np.trapz(intensity, p, axis=1)
    return float(np.trapz(over_phi * np.sin(t), t))
