"""The photometric mode's rules that relate several fields (docs/photometric.md): a named bulb's
filament, the custom filter's range, a file named where its kind reads none, and the names of the
measured curves a document gives (plain .csv file names beside it, found when the document is
loaded: ``beside.spectrum_files``); for parametric lamps and free-form parts alike."""

from __future__ import annotations

from . import spec as S
from .beside import check_plain_name
from .guide_checks import check_light_guide
from .messages import show_value
from .reading import SceneError

# The filaments (states) of each named bulb, as core_tracer.photometry.sources.BULB_TYPES gives them.
BULB_STATES = {"P21/5W": ("stop", "tail"), "R5W": ("on",), "PY21/5W": ("stop", "tail")}


def check_photometric(scene: dict) -> None:
    """Raise ``SceneError`` naming the field where the photometric fields do not fit together. The
    paper mode ignores them, but a named bulb's state and a file named where its kind reads none are
    checked in either mode (they are only set on purpose)."""
    for i, lamp in enumerate(scene["lamps"]):
        where = f"lamps[{i}]"
        _check_source(lamp["bulb"], f"{where}.bulb")
        _check_filter(lamp["lens"], f"{where}.lens")
        if lamp.get("collection", "reflector") == "prism_plate":  # else the plate is not traced at all
            _check_filter(lamp["prism_plate"], f"{where}.prism_plate")
        if lamp.get("light_guide", {}).get("enabled"):
            _check_filter(lamp["light_guide"], f"{where}.light_guide")
        check_light_guide(scene, i)
    for i, part in enumerate(scene.get("freeform", {}).get("parts", ())):
        role = part["role"]
        if role == "lens":
            _check_filter(part[role], f"freeform.parts[{i}].lens")
        elif role == "bulb":
            _check_source(part[role], f"freeform.parts[{i}].bulb")


# Per kind of part, the file field and the choice that reads it: (file key, choice key, the value that
# reads the file). A file named while its choice is another would be ignored without a word.
FILE_FIELDS = (("filter_file", "filter", "file"), ("spectrum_file", "spectrum", "file"))


def unused_files(section: dict) -> list[str]:
    """The file fields of a lens, plate or bulb section that name a file its choices do not read
    (a named bulb reads no spectrum file: its type gives the spectrum)."""
    out = []
    for key, choice, reads in FILE_FIELDS:
        if section.get(key) and (section.get(choice) != reads or section.get("type", "custom") != "custom"):
            out.append(key)
    return out


def _refuse_unused(section: dict, where: str) -> None:
    for key in unused_files(section):
        choice = next(c for k, c, _ in FILE_FIELDS if k == key)
        if section.get("type", "custom") != "custom":
            said = f'type is "{section["type"]}"'
        else:
            said = f'{choice} is "{section[choice]}"'
        raise SceneError(f"{where}.{key}", f'names a file while {said}, which reads none; allowed "" (or '
                                           f'{choice} "file" to read it)')


def _check_source(bulb: dict, where: str) -> None:
    _refuse_unused(bulb, where)
    if bulb["type"] != "custom":
        states = BULB_STATES[bulb["type"]]
        if bulb["state"] not in states:
            allowed = ", ".join(f'"{s}"' for s in states)
            raise SceneError(f"{where}.state", f'"{bulb["state"]}" is not a filament of a {bulb["type"]} '
                                               f"bulb; allowed one of {allowed}")
    elif bulb["spectrum"] == "file":
        check_plain_name(bulb["spectrum_file"], S.SPECTRUM_SUFFIXES, f"{where}.spectrum_file")


def _check_filter(part: dict, where: str) -> None:
    _refuse_unused(part, where)
    if part["filter"] == "file":
        check_plain_name(part["filter_file"], S.SPECTRUM_SUFFIXES, f"{where}.filter_file")
    elif part["filter"] == "custom":
        low, high = part["filter_range"]
        if low <= 0.0 or low > high:
            raise SceneError(f"{where}.filter_range", f"{show_value(part['filter_range'])} is not allowed; allowed "
                                                      "two transmittances 0 < below <= above <= 1")
