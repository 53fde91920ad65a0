"""The photometric mode's rules that relate several fields (docs/photometric.md): a named bulb's
filament, the custom filter's range, and the names of the measured curves a document gives (plain
.csv file names beside it, found when the document is loaded: ``beside.spectrum_files``)."""

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
    paper mode ignores them, but a named bulb's state is checked in either mode (it is only set on
    purpose)."""
    for i, lamp in enumerate(scene["lamps"]):
        where = f"lamps[{i}]"
        bulb = lamp["bulb"]
        if bulb["type"] != "custom":
            states = BULB_STATES[bulb["type"]]
            if bulb["state"] not in states:
                allowed = ", ".join(f'"{s}"' for s in states)
                raise SceneError(f"{where}.bulb.state", f'"{bulb["state"]}" is not a filament of a {bulb["type"]} '
                                                        f"bulb; allowed one of {allowed}")
        elif bulb["spectrum"] == "file":
            check_plain_name(bulb["spectrum_file"], S.SPECTRUM_SUFFIXES, f"{where}.bulb.spectrum_file")
        parts = [("lens", lamp["lens"])]
        if lamp.get("collection", "reflector") == "prism_plate":
            parts.append(("prism_plate", lamp["prism_plate"]))
        if lamp.get("light_guide", {}).get("enabled"):
            parts.append(("light_guide", lamp["light_guide"]))
        for name, part in parts:
            _check_filter(part, f"{where}.{name}")
        check_light_guide(scene, i)
    if scene.get("light_model") == "photometric" and "freeform" in scene:
        raise SceneError("light_model", '"photometric" is not available for free-form parts yet; allowed "paper" '
                                        "with a freeform section")


def _check_filter(part: dict, where: str) -> None:
    if part["filter"] == "file":
        check_plain_name(part["filter_file"], S.SPECTRUM_SUFFIXES, f"{where}.filter_file")
    elif part["filter"] == "custom":
        low, high = part["filter_range"]
        if low <= 0.0 or low > high:
            raise SceneError(f"{where}.filter_range", f"{show_value(part['filter_range'])} is not allowed; allowed "
                                                      "two transmittances 0 < below <= above <= 1")
