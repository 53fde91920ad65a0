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


def die_count(lamp: dict) -> int:
    """How many dies light a normalised LED lamp: its array's, twice over when its light guide is lit
    at both ends (the array and its mirror image, ``GuideTable.both_ends``)."""
    guide = lamp.get("light_guide") or {}
    both = bool(guide.get("enabled")) and guide.get("lit_ends", "one") == "both"
    return LedArray.of(lamp["led"]).count * (2 if both else 1)
