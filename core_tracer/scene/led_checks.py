"""The rules of a lamp's LED dies that relate several fields (docs/photometric.md, "LED sources"):
dies that do not overlap, an array that lies inside the lamp behind the cuts, and the names of the
files it reads (plain names beside the document, found when it is loaded: ``beside.spectrum_files``)."""

from __future__ import annotations

import numpy as np

from . import spec as S
from .beside import check_plain_name
from .led_array import LedArray
from .reading import SceneError


def check_leds(lamp: dict, g: dict, where: str) -> None:
    """Raise ``SceneError`` naming the field where a lamp's LED array does not fit."""
    led = lamp["led"]
    where = f"{where}.led"
    leds = LedArray.of(led)
    for axis, (count, name) in enumerate(((leds.columns, "across"), (leds.rows, "up"))):
        if count > 1 and leds.pitch[axis] < 2.0 * leds.half_size[axis]:
            raise SceneError(f"{where}.pitch", f"{leds.pitch[axis]:g} mm {name} is less than the die size "
                                               f"{2.0 * leds.half_size[axis]:g} mm: the dies overlap; allowed at "
                                               "least the die size")
    corners = np.array([c + sa * leds.half_size[0] * leds.across + sb * leds.half_size[1] * leds.up
                        for c in leds.die_centres() for sa in (-1, 1) for sb in (-1, 1)])
    if corners[:, 1].min() <= g["plane_b"]:
        raise SceneError(f"{where}.position", f"the dies reach y = {corners[:, 1].min():g} mm, in front of the back "
                                              f"of the cuts; allowed dies wholly behind y = {g['plane_b']:g} mm")
    if led["spectrum"] == "file":
        check_plain_name(led["spectrum_file"], S.SPECTRUM_SUFFIXES, f"{where}.spectrum_file")
    if led["distribution"] == "file":
        check_plain_name(led["far_field_file"], S.FAR_FIELD_SUFFIXES, f"{where}.far_field_file")
