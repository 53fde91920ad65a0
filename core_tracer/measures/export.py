"""The beam as a file lighting software reads: IES LM-63-2002 and EULUMDAT (.ldt).

A distribution on a (C, γ) grid (CIE 121 type C): γ the angle from the lamp's axis, C the azimuth
about it. The lamp's axis (its light toward −y) is the files' nadir (γ = 0); C = 0° points to +x, C =
90° to +z (up). To place a file in lighting software, aim the light's downward axis along the lamp's
axis. Values behind the lamp (γ above the measured range) are 0: the body hides the lamp there.

Formats:
- IES LM-63-2002 ("IES standard file format for the electronic transfer of photometric data and
  related information", IESNA 2002): the ``IESNA:LM-63-2002`` line, keyword lines (the four the
  standard requires: [TEST], [TESTLAB], [ISSUEDATE], [MANUFAC]; as listed by the eulumdat crate's
  IES module, docs.rs/eulumdat 0.6.0 ``ies.rs``, and photompy 0.3.1 ``ies_header.py``), ``TILT=NONE``,
  then number of lamps, lumens per lamp (−1: absolute photometry), candela multiplier, numbers of
  vertical and horizontal angles, photometric type (1 = C), units (2 = metres), luminous opening;
  ballast factor, file generation type, input watts; the angles and the candela values, one
  horizontal angle after another, in lines of at most 256 characters.
- EULUMDAT (Stockmar, "EULUMDAT: ein Leuchtendaten-Format für den europäischen Beleuchtungsplaner",
  LiTG 1990): 26 header lines (type indicator, symmetry, numbers and steps of C planes and γ angles,
  names, dimensions in mm, downward flux fraction, light output ratio, conversion factor, tilt, one
  set of lamps with its flux, colour and colour rendering), 10 direct ratios, the C and γ angles, and
  the intensities in cd per 1000 lm of the lamps' flux, C plane after C plane. A step of 0 means
  angles not equally spaced (the γ angles here: fine near the axis, coarser beyond).

The grid (``BeamGrid``): C every ``c_step`` degrees; γ every ``gamma_step`` up to ``NEAR_DEG`` (where a
signal lamp's beam and every regulation test point lie), then every ``far_step`` to 90°. The
default, C 10° × γ 2.5° to 50°, 5° beyond (1 009 directions): on the stop lamp the file integrates
to the light-traced flux leaving it within 0.1 % (51.40 lm for 51.44), and interpolating it (bilinear
in C and γ, as a lighting tool does) gives 34 of the report's 45 grid points within 2 %, the worst 6 %
(tests/measures/test_beam_files.py); 30° × 10° gave 113.7 cd for 121.7 at H-5R and 163 or 550 lm for
51 lm out of a 440 lm bulb. What is left is the estimates' scatter, not the grid: each node and each
report figure is a rendered estimate of two renders, and at 2 mm pixels one render of the stop lamp
scatters by 2–5 % off the axis (1–1.6 % at 1 mm, four times the time): C 5° × γ 1° was no closer.

Light output ratio (LORL) and downward flux fraction (DFF). The flux leaving the lamp is light-traced
(``light_tracing.traced_beam``: every photon counted where it leaves the lens), LORL = that over the
bulbs' flux; where light tracing does not follow the optics (cylindrical lenses, free-form parts) it
is the file's own integral, and the file says which. DFF is the share of the file's flux at γ < 90°
(the lamp's own hemisphere; the body hides the other).

Colour. A red or amber signal's light has no correlated colour temperature (CIE 015:2018 §9.5 defines
one only near the Planckian locus) and no colour rendering index: the files say "n/a" with the
light's xy. White light (a reversing lamp) gets its CCT from its xy (traced on the axis) by McCamy's
cubic (McCamy, "Correlated color temperature as an explicit function of chromaticity coordinates",
Color Res. Appl. 17, 142–144, 1992; within 2 K of the exact CCT from 2856 to 6504 K), and its CIE
13.3-1995 general colour rendering index Ra (``photometry.colour_rendering.general_cri``) from the
spectrum the lamp sends out (``emitted_spectrum``). The render gives only the traced light's xy, not
its spectrum, so that spectrum is an approximation: each lit source's spectrum at its flux times its
lens's (and prism plate's) filter transmittance at its thickness, summed; Fresnel losses and the
reflector's finish, both nearly flat over the visible, are left out. A paper design (no spectra) or
free-form parts give "n/a". Ra goes in the IES [LAMP] line and a user keyword [_COLORRENDERING]
(LM-63-2002 allows keywords beginning "_"), and in EULUMDAT's colour rendering field of the lamp set.
"""

from __future__ import annotations

import datetime
import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..photometry import sources
from ..photometry.bands import Bands
from ..photometry.colour_rendering import general_cri
from ..photometry.spectrum import Spectrum
from .directions import angles_of
from .intensity import Intensity, measured_together

IES_LINE = 256  # LM-63-2002: no line longer than 256 characters
NEAR_DEG = 50.0  # γ up to here at the fine step: every test point of R148 and FMVSS 108 (45° of AR at V 5°)
TRACED_PHOTONS = 50_000  # per lamp and source for the flux out: about 0.2 % standard error on the stop lamp
# A process's peak while it light-traces the flux out (batches of ``light_tracing.BATCH`` photons, not
# their count): 1,052 MB resident for the four-lamp night preset's four lamps (issue 34 item 2)
TRACED_FLUX_BYTES = 1100 * 2**20
MANUFACTURER = "Lamp Styling (simulated design, not a product)"


@dataclass(frozen=True)
class BeamGrid:
    """The (C, γ) angles of a beam file, in degrees (module docstring)."""

    c_step: float = 10.0
    gamma_step: float = 2.5
    far_step: float = 5.0

    def __post_init__(self):
        for what, value, lo, hi in (("C step", self.c_step, 1.0, 90.0), ("γ step", self.gamma_step, 0.25, 10.0),
                                    ("far γ step", self.far_step, 0.25, 45.0)):
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ValueError(f"{what}: {value!r} degrees is outside the allowed {lo:g} to {hi:g}")
        if 360.0 % self.c_step > 1e-9 or NEAR_DEG % self.gamma_step > 1e-9:
            raise ValueError(f"C step {self.c_step:g} and γ step {self.gamma_step:g}: allowed divisors of 360 and "
                             f"of {NEAR_DEG:g} degrees")

    @classmethod
    def parse(cls, text: str) -> BeamGrid:
        """``C,GAMMA[,FAR]`` in degrees (``--beam-grid``); raises ``ValueError`` naming the allowed form."""
        parts = text.split(",")
        try:
            numbers = [float(p) for p in parts]
        except ValueError:
            numbers = []
        if len(numbers) not in (2, 3):
            raise ValueError(f"{text!r} is not C,GAMMA or C,GAMMA,FAR (degrees, e.g. 5,1,5)")
        return cls(*numbers)

    def c_angles(self) -> np.ndarray:
        return np.arange(0.0, 360.0 - 1e-9, self.c_step)

    def gamma_angles(self) -> np.ndarray:
        near = np.arange(0.0, NEAR_DEG + 1e-9, self.gamma_step)
        far = np.arange(NEAR_DEG + self.far_step, 90.0 + 1e-9, self.far_step)
        angles = np.concatenate([near, far])
        return angles if angles[-1] >= 90.0 - 1e-9 else np.append(angles, 90.0)

    def text(self) -> str:
        return f"C {self.c_step:g}° × γ {self.gamma_step:g}° to {NEAR_DEG:g}°, {self.far_step:g}° beyond"


COARSE_GRID = BeamGrid(30.0, 10.0, 10.0)  # the grid of earlier versions, for quick looks


@dataclass(frozen=True)
class Distribution:
    """Luminous intensity ``cd[i, j]`` at C = ``c_deg[i]`` (0 ≤ C < 360) and γ = ``gamma_deg[j]``
    (from 0), of lamps whose bulbs emit ``flux_lm`` in all, of which ``out_lm`` leaves the lamp
    (light-traced, ± ``out_stderr_lm``; None: not traced, the file's integral stands for it)."""

    c_deg: np.ndarray
    gamma_deg: np.ndarray
    cd: np.ndarray
    flux_lm: float
    name: str = "lamp"
    out_lm: float | None = None
    out_stderr_lm: float | None = None
    xy: tuple[float, float] | None = None  # the light's chromaticity on the axis
    design: str = ""  # the scene's name
    date: str = ""  # ISO date of the measurement
    stderr: np.ndarray | None = None  # standard error of each ``cd`` (None: one replicate, not known)
    emitted: Spectrum | None = None  # the light's spectrum, for the colour rendering index (``emitted_spectrum``)

    def _weights(self, c: float, gamma: float) -> list[tuple[int, int, float]]:
        """The nodes (C index, γ index, weight) bilinear interpolation at (C, γ) sums, C periodic."""
        cs = np.append(self.c_deg, 360.0)
        c = c % 360.0
        i = int(np.clip(np.searchsorted(cs, c, side="right") - 1, 0, len(cs) - 2))
        tc = (c - cs[i]) / (cs[i + 1] - cs[i])
        j = int(np.clip(np.searchsorted(self.gamma_deg, gamma, side="right") - 1, 0, len(self.gamma_deg) - 2))
        tg = float(np.clip((gamma - self.gamma_deg[j]) / (self.gamma_deg[j + 1] - self.gamma_deg[j]), 0.0, 1.0))
        wrap = len(self.c_deg)
        return [(i % wrap, j, (1 - tc) * (1 - tg)), ((i + 1) % wrap, j, tc * (1 - tg)),
                (i % wrap, j + 1, (1 - tc) * tg), ((i + 1) % wrap, j + 1, tc * tg)]

    def at(self, c: float, gamma: float) -> float:
        """Bilinear in (C, γ), C periodic; 0 beyond the last γ."""
        if gamma > self.gamma_deg[-1]:
            return 0.0
        return float(sum(w * self.cd[i, j] for i, j, w in self._weights(c, gamma)))

    def integral_lm(self, below_deg: float = 180.0) -> float:
        """∫ I dΩ over γ < ``below_deg``, I bilinear between the angles (the trapezoid rule in C and
        in cos γ on each band: exact for I linear in C and in γ to second order)."""
        gamma = np.radians(self.gamma_deg)
        mean_c = self.cd.mean(axis=0)  # equal C steps: the mean over C of a bilinear I is the mean of the planes
        total = 0.0
        for j in range(len(gamma) - 1):
            if self.gamma_deg[j] >= below_deg:
                break
            g0, g1 = gamma[j], gamma[j + 1]
            # ∫ (I0 + (I1 − I0)(γ − g0)/(g1 − g0)) sin γ dγ over [g0, g1], exactly
            w1 = (math.sin(g1) - math.sin(g0) - (g1 - g0) * math.cos(g1)) / (g1 - g0)
            w0 = (math.cos(g0) - math.cos(g1)) - w1
            total += 2.0 * math.pi * (w0 * mean_c[j] + w1 * mean_c[j + 1])
        return float(total)

    @property
    def leaving_lm(self) -> float:
        """The flux leaving the lamp: traced, or the file's integral."""
        return self.out_lm if self.out_lm is not None else self.integral_lm()

    @property
    def lorl_percent(self) -> float:
        """Light output ratio: the flux leaving over the bulbs' flux, in %."""
        return 100.0 * self.leaving_lm / self.flux_lm if self.flux_lm > 0 else 0.0

    @property
    def dff_percent(self) -> float:
        """Downward flux fraction: the share of the file's flux at γ < 90°, in %."""
        total = self.integral_lm()
        return 100.0 * self.integral_lm(90.0) / total if total > 0 else 0.0


def gonio_direction(c_deg: float, gamma_deg: float) -> np.ndarray:
    """The light's direction at (C, γ): γ from the lamp's axis −y, C from +x toward +z."""
    c, g = math.radians(c_deg), math.radians(gamma_deg)
    return np.array([math.sin(g) * math.cos(c), -math.cos(g), math.sin(g) * math.sin(c)])


def measure_distribution(scene: dict, lamps: Sequence[int] | None = None, *, name: str = "lamp",
                         **options) -> Distribution:
    """The intensity of ``lamps`` (None: all) on a (C, γ) grid (``measure_distributions``)."""
    return measure_distributions(scene, {name: None if lamps is None else list(lamps)}, **options)[name]


def measure_distributions(scene: dict, groups: dict[str, Sequence[int] | None], *, grid: BeamGrid | None = None,
                          photons: int = TRACED_PHOTONS, progress: Callable[[str], None] | None = None,
                          **options) -> dict[str, Distribution]:
    """The intensity of each named group of lamps (None: all) on the (C, γ) ``grid``, by rendered
    views (``intensity.measured_together``, one render per direction for every group, on the local
    pool; ``options`` as ``rendered_intensities`` takes them), and the flux leaving each group,
    light-traced with ``photons`` (0: not traced) on the same pool beside the views."""
    grid = grid or BeamGrid()
    say = progress or (lambda text: None)
    lamp_lists = group_lamps(scene, groups)
    directions = beam_directions(grid)

    def counted(done: int, total: int) -> None:
        if done % 200 == 0 and done < total:
            say(f"beam files: direction {done + 1} of {total} ({grid.text()})")

    say(f"beam files: direction 1 of {len(directions)} ({grid.text()})")
    tasks = [(traced_flux, (scene, lamp_lists, photons))] if photons else []
    values, done = measured_together(scene, directions, lamp_lists, tasks=tasks, progress=counted, **options)
    return distributions(scene, list(groups), lamp_lists, grid, values, done[0] if photons else None)


def group_lamps(scene: dict, groups: dict[str, Sequence[int] | None]) -> list[list[int]]:
    """Each named group's lamps (None: all of them)."""
    return [list(range(len(scene["lamps"]))) if g is None else list(g) for g in groups.values()]


def beam_directions(grid: BeamGrid) -> list[tuple[float, float]]:
    """The (H, V) of each node of ``grid`` measured, γ by γ, C by C; every C plane meets at the axis:
    γ = 0 is measured once (C = 0)."""
    c, gamma = grid.c_angles(), grid.gamma_angles()
    return [tuple(float(a) for a in angles_of(gonio_direction(float(c[i]), float(g))))
            for g in gamma for i in range(len(c)) if not (g == 0.0 and i > 0)]


def traced_flux(scene: dict, lamp_lists: Sequence[Sequence[int]], photons: int) -> list[tuple[float, float] | None]:
    """The flux in lm (and its standard error) leaving each group of lamps, light-traced with
    ``photons`` per lamp and source (``light_tracing.traced_beam``); None for each where light tracing
    does not follow the optics (the file's integral stands for the flux out)."""
    from ..scene.reading import SceneError
    from .light_tracing import traced_beam

    try:
        return traced_beam(scene, [(0.0, 0.0)], lamp_lists, photons=photons)[1]  # its flux out, not the cone
    except SceneError:
        return [None] * len(lamp_lists)


def distributions(scene: dict, names: Sequence[str], lamp_lists: Sequence[Sequence[int]], grid: BeamGrid,
                  values: Sequence[Sequence[Intensity]], traced: Sequence[tuple[float, float] | None] | None
                  ) -> dict[str, Distribution]:
    """Each group's ``Distribution`` from the intensities measured at ``beam_directions(grid)`` and the
    light-traced flux leaving it (None: not traced)."""
    c, gamma = grid.c_angles(), grid.gamma_angles()
    cd = np.zeros((len(names), len(c), len(gamma)))
    err = np.zeros_like(cd)
    axis_xyz = [np.zeros(3) for _ in names]
    cells = [(i, j) for j, g in enumerate(gamma) for i in range(len(c)) if not (g == 0.0 and i > 0)]
    for (i, j), at in zip(cells, values, strict=True):
        for k, value in enumerate(at):
            cd[k, i, j], err[k, i, j] = value.cd, value.stderr
            if gamma[j] == 0.0:
                axis_xyz[k] = value.xyz
    for j, g in enumerate(gamma):
        if g == 0.0:
            cd[:, 1:, j], err[:, 1:, j] = cd[:, :1, j], err[:, :1, j]
    traced = traced or [None] * len(names)
    date = datetime.datetime.now(datetime.UTC).date().isoformat()
    out = {}
    for k, n in enumerate(names):
        s = float(np.sum(axis_xyz[k]))
        xy = (float(axis_xyz[k][0] / s), float(axis_xyz[k][1] / s)) if s > 0 else None
        out[n] = Distribution(c, gamma, cd[k], lamp_flux(scene, lamp_lists[k]), n,
                              traced[k][0] if traced[k] else None, traced[k][1] if traced[k] else None,
                              xy, str(scene.get("name", "")), date,
                              err[k] if np.isfinite(err[k]).all() else None,
                              emitted_spectrum(scene, lamp_lists[k]))
    return out


def lamp_flux(scene: dict, lamps: Sequence[int] | None = None) -> float:
    """The luminous flux in lm of the lit bulbs (or LED dies) of ``lamps`` (None: all); of a free-form
    design, of its lit bulb parts (the design is one lamp, ``intensity.lamp_of_pixels``)."""
    from ..raytrace.spectral import bulb_spectrum
    from ..scene.led_array import die_count, uses_leds

    total = 0.0
    if "freeform" in scene:
        for i, part in enumerate(scene["freeform"]["parts"]):
            if part["role"] == "bulb" and part["bulb"]["on"]:
                total += bulb_spectrum(part["bulb"], f"freeform.parts[{i}].bulb")[0]
        return float(total)
    for i, lamp in enumerate(scene["lamps"]):
        if (lamps is None or i in lamps) and lamp["bulb"]["on"]:
            if uses_leds(lamp):  # the dies' flux, each into its half space
                total += lamp["led"]["flux_lm"] * die_count(lamp)
            else:
                total += bulb_spectrum(lamp["bulb"], f"lamps[{i}].bulb")[0]
    return float(total)


def mccamy_cct(xy: tuple[float, float]) -> float:
    """CCT in K from CIE 1931 xy: n = (x − 0.3320)/(0.1858 − y), CCT = 449 n³ + 3525 n² + 6823.3 n +
    5520.33 (McCamy 1992)."""
    n = (xy[0] - 0.3320) / (0.1858 - xy[1])
    return 449.0 * n**3 + 3525.0 * n**2 + 6823.3 * n + 5520.33


# 5 nm bands centred on 360, 365, ..., 830 nm: CIE 13.3's grid for the colour rendering index
RA_BANDS = Bands(np.arange(357.5, 832.5 + 1e-9, 5.0))


def emitted_spectrum(scene: dict, lamps: Sequence[int] | None = None) -> Spectrum | None:
    """The relative spectral power ``lamps`` (None: all) send out, approximated as each lit source's
    spectrum at its flux (per lumen, times lm) times its lens's and prism plate's filter transmittance
    at their thickness, summed over the lamps (module docstring); None for a paper design, free-form
    parts, or no lit source."""
    from ..raytrace import spectral
    from ..scene.led_array import die_count, uses_leds

    if scene.get("light_model", "paper") != "photometric" or "freeform" in scene:
        return None
    total = np.zeros(RA_BANDS.k)
    for i in range(len(scene["lamps"])) if lamps is None else lamps:
        lamp, where = scene["lamps"][i], f"lamps[{i}]"
        if not lamp["bulb"]["on"]:
            continue
        if uses_leds(lamp):
            flux = lamp["led"]["flux_lm"] * die_count(lamp)
            spectrum = spectral.led_spectrum(lamp["led"], f"{where}.led")
        else:
            flux, spectrum = spectral.bulb_spectrum(lamp["bulb"], f"{where}.bulb")
        light = flux * sources.spectral_shape(spectrum, RA_BANDS)
        parts = ["lens"] + (["prism_plate"] if lamp.get("collection", "reflector") == "prism_plate" else [])
        for part in parts:
            light = light * spectral.filter_transmittance(lamp[part], RA_BANDS, f"{where}.{part}")
        total += light
    if not total.any():
        return None
    return Spectrum(RA_BANDS.centres_nm, total, "the lamp's light")


def light_colour(dist: Distribution) -> tuple[str, str, str]:
    """(what the light is, the CCT field, the colour rendering field) for the files' lamp data: CCT
    and Ra for white light (Ra "n/a" without the emitted spectrum), "n/a" for both otherwise."""
    from . import colour

    if dist.xy is None:
        return "no light on the axis", "n/a", "n/a"
    x, y = dist.xy
    where = f"x {x:.3f} y {y:.3f}"
    for name in ("red", "amber"):
        if colour.inside(dist.xy, colour.REGIONS["UN R48 §2.29"][name]):
            return f"{name} light ({where}): no CCT, colour rendering n/a", "n/a", "n/a"
    if colour.inside(dist.xy, colour.REGIONS["UN R48 §2.29"]["white"]):
        cct = mccamy_cct(dist.xy)
        if dist.emitted is None:
            return f"white light ({where}), CCT {cct:.0f} K, colour rendering not known", f"{cct:.0f}K", "n/a"
        ra = general_cri(dist.emitted.wavelengths_nm, dist.emitted.values)
        return (f"white light ({where}), CCT {cct:.0f} K, Ra {ra:.0f} (CIE 13.3, source spectrum times lens filter)",
                f"{cct:.0f}K", f"{ra:.0f}")
    return f"coloured light ({where}): no CCT, colour rendering n/a", "n/a", "n/a"


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


def _behind(dist: Distribution) -> list[float]:
    """The γ angles past the measured ones up to 180° (intensity 0: the body hides the lamp)."""
    gamma = list(dist.gamma_deg)
    step = gamma[-1] - gamma[-2] if len(gamma) > 1 else 90.0
    behind = list(np.arange(gamma[-1] + step, 180.0 + 1e-9, step))
    if not behind or behind[-1] < 180.0:
        behind.append(180.0)
    return behind


def _flux_note(dist: Distribution) -> str:
    if dist.out_lm is not None:
        return f"{dist.out_lm:.4g} lm leave the lamp (light-traced, standard error {dist.out_stderr_lm:.2g} lm)"
    return f"{dist.leaving_lm:.4g} lm leave the lamp (the file's integral; light tracing does not follow these optics)"


def _title(dist: Distribution) -> str:
    return f"{dist.design}, {dist.name} function" if dist.design else f"{dist.name} function"


def ies_text(dist: Distribution, *, test: str = "simulated by core_tracer.measures",
             opening_m: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> str:
    """The distribution as IES LM-63-2002 text (absolute photometry, type C, 0–180° vertical, 0–360°
    horizontal)."""
    behind = _behind(dist)
    vertical = list(dist.gamma_deg) + behind
    horizontal = list(dist.c_deg) + [360.0]
    date = dist.date or datetime.date.today().isoformat()
    what, _, rendering = light_colour(dist)
    lines = ["IESNA:LM-63-2002", f"[TEST] {test}", "[TESTLAB] Lamp Styling (simulation, not a laboratory)",
             f"[ISSUEDATE] {date}", f"[MANUFAC] {MANUFACTURER}", f"[LUMINAIRE] {_safe(_title(dist))}",
             f"[LAMP] lit bulbs, {dist.flux_lm:g} lm in all; {_safe(what)}", f"[_COLORRENDERING] {rendering}",
             f"[OTHER] {_flux_note(dist)}: light output ratio {dist.lorl_percent:.1f} %",
             "[MORE] lamp axis = nadir; C0 toward +x, C90 toward +z (docs/measures.md)", "TILT=NONE",
             f"1 -1 1 {len(vertical)} {len(horizontal)} 1 2 {opening_m[0]:g} {opening_m[1]:g} {opening_m[2]:g}",
             "1 1 0"]
    lines += _lines_of(vertical, "{:g}") + _lines_of(horizontal, "{:g}")
    rows = list(dist.cd) + [dist.cd[0]]
    for row in rows:
        lines += _lines_of(list(row) + [0.0] * len(behind))
    return "\r\n".join(_safe(line) for line in lines) + "\r\n"


def ldt_text(dist: Distribution, *, company: str = MANUFACTURER, report: str = "simulated",
             file_name: str | None = None) -> str:
    """The distribution as EULUMDAT text (no symmetry; intensities in cd/klm of the bulbs' flux)."""
    if not dist.flux_lm > 0:
        raise ValueError("EULUMDAT: the lamps' flux is 0 lm; allowed a design with a lit bulb (cd/klm needs it)")
    g_all = list(dist.gamma_deg) + _behind(dist)
    steps = np.diff(g_all)
    dg = steps[0] if np.allclose(steps, steps[0]) else 0.0  # 0: angles not equally spaced (listed below)
    per_klm = dist.cd * 1000.0 / dist.flux_lm
    dc = dist.c_deg[1] - dist.c_deg[0] if len(dist.c_deg) > 1 else 360.0
    _, cct, rendering = light_colour(dist)
    name = file_name or f"{dist.name}.ldt"
    header = [
        company[:78], "3", "0", str(len(dist.c_deg)), f"{dc:g}", str(len(g_all)), f"{dg:g}", report[:78],
        _safe(_title(dist))[:78], dist.name[:78], _safe(name)[:8 + 1 + 3 + 66], f"{dist.date} core_tracer"[:78],
        "0", "0", "0", "0", "0", "0", "0", "0", "0",  # dimensions (mm): not a luminaire's housing
        f"{dist.dff_percent:.1f}", f"{dist.lorl_percent:.1f}", "1", "0",  # DFF, LORL (%), factor, tilt
        "1", "1", "lit bulbs", f"{dist.flux_lm:g}", cct[:16], rendering[:6], "0",
    ]
    lines = header + ["0"] * 10
    lines += [f"{c:g}" for c in dist.c_deg] + [f"{g:g}" for g in g_all]
    for row in per_klm:
        lines += [f"{v:.6g}" for v in list(row) + [0.0] * (len(g_all) - len(row))]
    return "\r\n".join(lines) + "\r\n"


def write_ies(dist: Distribution, path: str | os.PathLike) -> None:
    _write(path, ies_text(dist))


def write_ldt(dist: Distribution, path: str | os.PathLike) -> None:
    _write(path, ldt_text(dist, file_name=os.path.basename(os.fspath(path))))


def _write(path, text: str) -> None:
    tmp = f"{os.fspath(path)}.part"
    with open(tmp, "w", encoding="ascii", errors="replace", newline="") as f:
        f.write(text)
    os.replace(tmp, path)


def _safe(text: str) -> str:
    return "".join(ch if 32 <= ord(ch) < 127 else "?" for ch in str(text))
