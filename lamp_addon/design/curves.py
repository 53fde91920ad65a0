"""The measured curves (.csv) a photometric design names, found in Blender: beside the saved .blend
file, or beside the preset the design was applied from.

A design names a bulb's spectrum or a filter's transmittance by a plain file name
(``bulb.spectrum_file``, ``filter_file``), as a preset does beside its JSON
(``core_tracer.scene.beside``). In Blender the design lives in the .blend file, so its folder is
looked in first; a preset applied from a file leaves its folder on the scene (``FOLDER_KEY``), looked
in next, so that a preset with its curves renders as it came.
"""

from __future__ import annotations

import os

import bpy

from ...core_tracer.scene import beside
from ...core_tracer.scene.reading import SceneError

FOLDER_KEY = "lamp_curves_folder"  # scene custom property: the folder of the preset applied last


def remember_preset_folder(bl_scene, preset_path: str) -> None:
    """Look for curves beside ``preset_path`` too (after the .blend file's folder)."""
    bl_scene[FOLDER_KEY] = os.path.dirname(os.path.abspath(preset_path))


def folders(bl_scene) -> list[str]:
    """Where curves are looked for, in order: the saved .blend file's folder, the applied preset's."""
    out = []
    if bpy.data.filepath:
        out.append(os.path.dirname(os.path.abspath(bpy.data.filepath)))
    preset = bl_scene.get(FOLDER_KEY)
    if isinstance(preset, str) and preset and preset not in out:
        out.append(preset)
    return out


def with_curves(bl_scene, scene: dict) -> dict:
    """``scene`` (normalised) with the curves it names by their full paths, found in ``folders``;
    the scene itself when it names none. Raises ``SceneError`` naming the field when a curve is in
    none of them."""
    if scene.get("light_model", "paper") != "photometric":
        return scene
    places = folders(bl_scene)
    first_error = None
    for folder in places:
        try:
            found = beside.with_spectrum_files(os.path.join(folder, "design.json"), scene)
        except SceneError as e:
            first_error = first_error or e
            continue
        return checked(found)
    if first_error is None:  # no folder to look in: fine only when no curve is named
        try:
            beside.with_spectrum_files(os.path.join(os.sep, "nowhere", "design.json"), scene)
        except SceneError as e:
            raise SceneError(e.path, "is read beside the .blend file: save the .blend file in the curve's folder "
                                     "first; allowed a .csv file beside the saved .blend file or the preset") from None
        return checked(scene)
    where = " or ".join(f'"{folder}"' for folder in places)
    raise SceneError(first_error.path, f"{first_error.message.split(';')[0]} in {where}; allowed a .csv file beside "
                                       "the saved .blend file or the preset it came from")


def checked(scene: dict) -> dict:
    """``scene`` once every check its render makes on its spectra passed (``raytrace.spectral.check_lamps``:
    visible light, finite luminance, filters' transmittance), as ``validate`` makes them."""
    from ...core_tracer.raytrace import spectral

    spectral.check_lamps(scene)
    return scene
