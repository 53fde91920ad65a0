"""Where a lamp's LED dies are (docs/photometric.md, "LED sources"): a grid of flat dies in one plane.

The array's frame: the unit normal n the dies face, the direction ``up`` (the world's +z made
perpendicular to n; +y when n is vertical) and ``across`` = up × n, so that a die facing the lens
(n = −y) has across = +x and up = +z, the axes of the exported far-field files (C 0° toward +x,
C 90° toward +z: ``measures.export``). Die (i, j), i across and j up, has its centre at
position + (i − (columns − 1)/2) pitch_across · across + (j − (rows − 1)/2) pitch_up · up.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class LedArray:
    """One lamp's LED array in the lamp's frame (mm)."""

    center: np.ndarray  # (3,) the array's centre
    normal: np.ndarray  # (3,) unit, the side the dies emit from
    across: np.ndarray  # (3,) unit
    up: np.ndarray  # (3,) unit
    half_size: np.ndarray  # (2,) half width (across) and half height (up) of a die
    pitch: np.ndarray  # (2,) centre-to-centre across and up
    columns: int
    rows: int

    @classmethod
    def of(cls, led: dict) -> LedArray:
        """The array of a normalised ``led`` section."""
        normal = np.asarray(led["normal"], dtype=np.float64)
        normal = normal / np.linalg.norm(normal)
        hint = np.array([0.0, 0.0, 1.0]) if abs(normal[2]) < 0.999 else np.array([0.0, 1.0, 0.0])
        up = hint - (hint @ normal) * normal
        up /= np.linalg.norm(up)
        across = np.cross(up, normal)
        return cls(np.asarray(led["position"], dtype=np.float64), normal, across, up,
                   0.5 * np.asarray(led["die_size"], dtype=np.float64), np.asarray(led["pitch"], dtype=np.float64),
                   int(led["columns"]), int(led["rows"]))

    def mirrored(self, point: np.ndarray, axis: np.ndarray) -> LedArray:
        """The array's mirror image through the plane through ``point`` normal to unit ``axis``: x' = x −
        2 ((x − p)·a) a. A reflection turns across × up into −(across' × up'), so across' is the image of
        −across: the dies keep facing their normal (their grid, symmetric about its centre, is the image's)."""
        def image(v: np.ndarray) -> np.ndarray:
            return v - 2.0 * (v @ axis) * axis
        return LedArray(self.center - 2.0 * ((self.center - point) @ axis) * axis, image(self.normal),
                        -image(self.across), image(self.up), self.half_size, self.pitch, self.columns, self.rows)

    @property
    def count(self) -> int:
        return self.columns * self.rows

    @property
    def die_area_mm2(self) -> float:
        return float(4.0 * self.half_size[0] * self.half_size[1])

    def die_centres(self) -> np.ndarray:
        """(count, 3) the dies' centres, across first."""
        i = np.arange(self.columns) - (self.columns - 1) / 2.0
        j = np.arange(self.rows) - (self.rows - 1) / 2.0
        a, b = np.meshgrid(i * self.pitch[0], j * self.pitch[1], indexing="xy")
        return self.center + a.reshape(-1, 1) * self.across + b.reshape(-1, 1) * self.up


def uses_leds(lamp: dict) -> bool:
    """Whether a normalised lamp's light source is its LED dies (else its bulb)."""
    return lamp.get("source", "bulb") == "led"


def mirror_plane(guide: dict) -> tuple[np.ndarray, np.ndarray]:
    """The middle of a normalised light guide and its unit axis (lamp frame): the plane s = L/2 through
    which a guide lit at both ends mirrors its lamp's LED array (``raytrace.guide_table``)."""
    theta = np.radians(guide["orientation"])
    return (np.array([guide["center"][0], guide["depth"], guide["center"][1]], dtype=np.float64),
            np.array([np.cos(theta), 0.0, np.sin(theta)]))


def lit_arrays(lamp: dict) -> list[LedArray]:
    """The LED arrays that light a normalised LED lamp: its own, and when its light guide is lit at both
    ends (``lit_ends`` "both") that array's mirror image through the guide's middle."""
    leds = LedArray.of(lamp["led"])
    guide = lamp.get("light_guide") or {}
    if not guide.get("enabled") or guide.get("lit_ends", "one") != "both":
        return [leds]
    return [leds, leds.mirrored(*mirror_plane(guide))]


def die_count(lamp: dict) -> int:
    """How many dies light a normalised LED lamp: its array's, twice over when its light guide is lit
    at both ends (the array and its mirror image, ``lit_arrays``)."""
    return sum(leds.count for leds in lit_arrays(lamp))
