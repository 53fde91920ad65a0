"""The beam as a file lighting software reads: IES LM-63-2002 and EULUMDAT (.ldt).

A distribution on a (C, γ) grid (CIE 121 type C): γ the angle from the lamp's axis, C the azimuth
about it. The lamp's axis (its light toward −y) is the files' nadir (γ = 0); C = 0° points to +x, C =
90° to +z (up). To place a file in lighting software, aim the light's downward axis along the lamp's
axis. Values behind the lamp (γ above the measured range) are 0: the body hides the lamp there.

Formats:
- IES LM-63-2002 ("IES standard file format for the electronic transfer of photometric data and
  related information", IESNA 2002): the ``IESNA:LM-63-2002`` line, keyword lines, ``TILT=NONE``,
  then number of lamps, lumens per lamp (−1: absolute photometry), candela multiplier, numbers of
  vertical and horizontal angles, photometric type (1 = C), units (2 = metres), luminous opening;
  ballast factor, file generation type, input watts; the angles and the candela values, one
  horizontal angle after another, in lines of at most 256 characters.
- EULUMDAT (Stockmar, "EULUMDAT: ein Leuchtendaten-Format für den europäischen Beleuchtungsplaner",
  LiTG 1990): 26 header lines (type indicator, symmetry, numbers and steps of C planes and γ angles,
  names, dimensions in mm, downward flux fraction, light output ratio, conversion factor, tilt, one
  set of lamps with its flux), 10 direct ratios, the C and γ angles, and the intensities in cd per
  1000 lm of the lamps' flux, C plane after C plane.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .directions import angles_of
from .intensity import intensities_at

IES_LINE = 256  # LM-63-2002: no line longer than 256 characters


@dataclass(frozen=True)
class Distribution:
    """Luminous intensity ``cd[i, j]`` at C = ``c_deg[i]`` (0 ≤ C < 360) and γ = ``gamma_deg[j]``
    (from 0), of lamps whose bulbs emit ``flux_lm`` in all."""

    c_deg: np.ndarray
    gamma_deg: np.ndarray
    cd: np.ndarray
    flux_lm: float
    name: str = "lamp"

    def at(self, c: float, gamma: float) -> float:
        """Bilinear in (C, γ), C periodic; 0 beyond the last γ."""
        if gamma > self.gamma_deg[-1]:
            return 0.0
        cs = np.append(self.c_deg, 360.0)
        table = np.vstack([self.cd, self.cd[:1]])
        c = c % 360.0
        i = int(np.clip(np.searchsorted(cs, c, side="right") - 1, 0, len(cs) - 2))
        tc = (c - cs[i]) / (cs[i + 1] - cs[i])
        row = (1 - tc) * table[i] + tc * table[i + 1]
        return float(np.interp(gamma, self.gamma_deg, row))


def gonio_direction(c_deg: float, gamma_deg: float) -> np.ndarray:
    """The light's direction at (C, γ): γ from the lamp's axis −y, C from +x toward +z."""
    c, g = math.radians(c_deg), math.radians(gamma_deg)
    return np.array([math.sin(g) * math.cos(c), -math.cos(g), math.sin(g) * math.sin(c)])


def measure_distribution(scene: dict, lamps: Sequence[int] | None = None, *, name: str = "lamp",
                         **options) -> Distribution:
    """The intensity of ``lamps`` (None: all) on a (C, γ) grid (``measure_distributions``)."""
    return measure_distributions(scene, {name: None if lamps is None else list(lamps)}, **options)[name]


def measure_distributions(scene: dict, groups: dict[str, Sequence[int] | None], *, c_step: float = 30.0,
                          gamma_step: float = 10.0, gamma_max: float = 90.0, **options) -> dict[str, Distribution]:
    """The intensity of each named group of lamps (None: all) on a (C, γ) grid, by rendered views
    (``intensity.intensities_at``, one render per direction for every group; ``options`` as
    ``rendered_intensities`` takes them)."""
    for what, value, lo, hi in (("C step", c_step, 1.0, 180.0), ("γ step", gamma_step, 1.0, 90.0),
                                ("γ max", gamma_max, 1.0, 90.0)):
        if not (math.isfinite(value) and lo <= value <= hi):
            raise ValueError(f"{what}: {value!r} degrees is outside {lo:g} to {hi:g}")
    c = np.arange(0.0, 360.0 - 1e-9, c_step)
    gamma = np.arange(0.0, gamma_max + 1e-9, gamma_step)
    names = list(groups)
    lamp_lists = [list(range(len(scene["lamps"]))) if groups[n] is None else list(groups[n]) for n in names]
    cd = np.zeros((len(names), len(c), len(gamma)))
    # Every C plane meets at the axis: γ = 0 is measured once (C = 0). The directions are measured
    # together, on the local pool (``intensity.intensities_at``).
    grid = [(i, j) for j, g in enumerate(gamma) for i in range(len(c)) if not (g == 0.0 and i > 0)]
    directions = [tuple(float(a) for a in angles_of(gonio_direction(float(c[i]), float(gamma[j])))) for i, j in grid]
    for (i, j), at in zip(grid, intensities_at(scene, directions, lamp_lists, **options), strict=True):
        for k, value in enumerate(at):
            cd[k, i, j] = value.cd
    for j, g in enumerate(gamma):
        if g == 0.0:
            cd[:, 1:, j] = cd[:, :1, j]
    return {n: Distribution(c, gamma, cd[k], lamp_flux(scene, lamp_lists[k]), n) for k, n in enumerate(names)}


def lamp_flux(scene: dict, lamps: Sequence[int] | None = None) -> float:
    """The luminous flux in lm of the lit bulbs (or LED dies) of ``lamps`` (None: all); of a free-form
    design, of its lit bulb parts (the design is one lamp, ``intensity.lamp_of_pixels``)."""
    from ..raytrace.spectral import bulb_spectrum
    from ..scene.led_array import LedArray, uses_leds

    total = 0.0
    if "freeform" in scene:
        for i, part in enumerate(scene["freeform"]["parts"]):
            if part["role"] == "bulb" and part["bulb"]["on"]:
                total += bulb_spectrum(part["bulb"], f"freeform.parts[{i}].bulb")[0]
        return float(total)
    for i, lamp in enumerate(scene["lamps"]):
        if (lamps is None or i in lamps) and lamp["bulb"]["on"]:
            if uses_leds(lamp):  # the dies' flux, each into its half space
                total += lamp["led"]["flux_lm"] * LedArray.of(lamp["led"]).count
            else:
                total += bulb_spectrum(lamp["bulb"], f"lamps[{i}].bulb")[0]
    return float(total)


def _lines_of(values: Sequence[float], fmt: str = "{:.6g}") -> list[str]:
    """Numbers joined by spaces in lines no longer than ``IES_LINE``."""
    lines, line = [], ""
    for text in (fmt.format(v) for v in values):
        if line and len(line) + 1 + len(text) > IES_LINE:
            lines.append(line)
            line = text
        else:
            line = f"{line} {text}" if line else text
    if line:
        lines.append(line)
    return lines


def ies_text(dist: Distribution, *, test: str = "simulated by core_tracer.measures",
             opening_m: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> str:
    """The distribution as IES LM-63-2002 text (absolute photometry, type C, 0–180° vertical, 0–360°
    horizontal)."""
    gamma = list(dist.gamma_deg)
    cd = dist.cd
    step = gamma[1] - gamma[0] if len(gamma) > 1 else 90.0
    behind = list(np.arange(gamma[-1] + step, 180.0 + 1e-9, step))
    if not behind or behind[-1] < 180.0:
        behind.append(180.0)
    vertical = gamma + behind
    horizontal = list(dist.c_deg) + [360.0]
    lines = ["IESNA:LM-63-2002", f"[TEST] {test}", "[TESTLAB] Lamp Styling",
             f"[LUMINAIRE] {_safe(dist.name)}", f"[LAMP] lit bulbs, {dist.flux_lm:g} lm in all",
             "[OTHER] lamp axis = nadir; C0 toward +x, C90 toward +z (docs/measures.md)", "TILT=NONE",
             f"1 -1 1 {len(vertical)} {len(horizontal)} 1 2 {opening_m[0]:g} {opening_m[1]:g} {opening_m[2]:g}",
             "1 1 0"]
    lines += _lines_of(vertical, "{:g}") + _lines_of(horizontal, "{:g}")
    rows = list(cd) + [cd[0]]
    for row in rows:
        lines += _lines_of(list(row) + [0.0] * len(behind))
    return "\r\n".join(lines) + "\r\n"


def ldt_text(dist: Distribution, *, company: str = "Lamp Styling", report: str = "simulated") -> str:
    """The distribution as EULUMDAT text (no symmetry; intensities in cd/klm of the bulbs' flux)."""
    if not dist.flux_lm > 0:
        raise ValueError("EULUMDAT: the lamps' flux is 0 lm; allowed a design with a lit bulb (cd/klm needs it)")
    gamma = list(dist.gamma_deg)
    step = gamma[1] - gamma[0] if len(gamma) > 1 else 90.0
    behind = list(np.arange(gamma[-1] + step, 180.0 + 1e-9, step))
    g_all = gamma + behind
    per_klm = dist.cd * 1000.0 / dist.flux_lm
    dc = dist.c_deg[1] - dist.c_deg[0] if len(dist.c_deg) > 1 else 360.0
    header = [
        company[:78], "3", "0", str(len(dist.c_deg)), f"{dc:g}", str(len(g_all)), f"{step:g}", report[:78],
        _safe(dist.name)[:78], "", "lamp.ldt", "core_tracer.measures",
        "0", "0", "0", "0", "0", "0", "0", "0", "0",  # dimensions (mm): not a luminaire's housing
        "0", "100", "1", "0",  # DFF, LORL (the flux leaving is counted in the intensities), factor, tilt
        "1", "1", "lit bulbs", f"{dist.flux_lm:g}", "2856", "100", "0",
    ]
    lines = header + ["0"] * 10
    lines += [f"{c:g}" for c in dist.c_deg] + [f"{g:g}" for g in g_all]
    for row in per_klm:
        lines += [f"{v:.6g}" for v in list(row) + [0.0] * len(behind)]
    return "\r\n".join(lines) + "\r\n"


def write_ies(dist: Distribution, path: str | os.PathLike) -> None:
    _write(path, ies_text(dist))


def write_ldt(dist: Distribution, path: str | os.PathLike) -> None:
    _write(path, ldt_text(dist))


def _write(path, text: str) -> None:
    tmp = f"{os.fspath(path)}.part"
    with open(tmp, "w", encoding="ascii", errors="replace", newline="") as f:
        f.write(text)
    os.replace(tmp, path)


def _safe(text: str) -> str:
    return "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in str(text))
