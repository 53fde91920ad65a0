"""Which fields each light model uses (``light_model``: paper or photometric), for editors that
show only what shapes the image.

The photometric mode's own fields say "Photometric" first in their description (``spec``); the
paper mode ignores them. The photometric mode ignores the paper's appearance values
(``raytrace.spectral``): the bulb's RGB intensity, the reflector's constant colour, mirror
reflectance and Blinn weight (its finish and glow share stand for them), the unlit colours of the
lens surface, its rim, the socket and the plate's housing (they end a path with 0), the lens colour
as RGB absorption (its filter stands for it), the plate's RGB absorption, the sun's colour, strength,
highlight colour and ambient (the sun is CIE daylight at its illuminance in lux), the environment's
strength (its illuminance or luminance scales it) and the background colour (black). The lens's
refractive index is its material's unless the material is custom.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from . import spec as S
from .messages import show_value

PHOTOMETRIC_PREFIX = "Photometric"

# (section, keys the photometric mode ignores)
_PAPER_ONLY = (
    (S.SCENE, ("background",)),
    (S.LIGHT, ("color", "ambient", "strength", "sun_color", "follow_environment_color")),
    (S.ENVIRONMENT, ("strength",)),
    (S.LENS, ("absorption", "transmitted_color", "reference_thickness", "diffuse_color", "side_wall_color")),
    (S.REFLECTOR, ("color", "reflectance", "scatter")),
    (S.BULB, ("intensity",)),
    (S.SOCKET, ("color",)),
    (S.PRISM_PLATE, ("absorption", "housing_color")),
    # free-form parts: as the parametric parts they stand for (docs/photometric.md, "Free-form parts")
    (S.FREEFORM_ROLE_SECTIONS["lens"], ("absorption", "transmitted_color", "reference_thickness", "diffuse_color")),
    (S.FREEFORM_ROLE_SECTIONS["reflector"], ("color", "reflectance", "scatter")),
    (S.FREEFORM_ROLE_SECTIONS["bulb"], ("intensity",)),
    (S.FREEFORM_ROLE_SECTIONS["socket"], ("color",)),
    (S.FREEFORM_ROLE_SECTIONS["side_wall"], ("color",)),
)
# (section, key, choice key, values): shown in the photometric mode only while the choice holds
# one of the values (the paper mode always uses the field)
_PHOTOMETRIC_SHOWN_WHEN = ((S.LENS, "ior", "material", ("custom",)),
                           (S.FREEFORM_ROLE_SECTIONS["lens"], "ior", "material", ("custom",)))


def is_photometric_only(section: S.Section, key: str) -> bool:
    """Whether ``key`` of ``section`` means something in the photometric mode only."""
    return section.fields[key].doc.startswith(PHOTOMETRIC_PREFIX)


def is_paper_only(section: S.Section, key: str) -> bool:
    """Whether the photometric mode ignores ``key`` of ``section``."""
    return any(sec is section and key in keys for sec, keys in _PAPER_ONLY)


def used(section: S.Section, key: str, light_model: str, value_of: Callable[[str], object]) -> bool:
    """Whether field ``key`` of ``section`` shapes the image under ``light_model``; ``value_of``
    gives the section's other fields (a custom material's index)."""
    if light_model == "photometric":
        if is_paper_only(section, key):
            return False
        return all(value_of(choice) in values for sec, k, choice, values in _PHOTOMETRIC_SHOWN_WHEN
                   if sec is section and k == key)
    return not is_photometric_only(section, key)


# At most this many fields are named in the note; the rest are counted.
_NAMED_AT_MOST = 3


def ignored_fields(scene: dict) -> list[tuple[str, object]]:
    """``(path, value)`` of each photometric field a paper-mode ``scene`` (normalised) sets to other
    than its default: the values the paper light model ignores. A field at its default is not
    listed, so a document that writes every field (a preset saved by Blender) says nothing."""
    if scene.get("light_model", "paper") != "paper":
        return []
    out = []
    for path, value in _leaves(scene, S.SCENE, ""):
        spec = S.lookup(re.sub(r"\[\d+\]", "[]", path))
        default = list(spec.default) if isinstance(spec.default, tuple) else spec.default
        if spec.doc.startswith(PHOTOMETRIC_PREFIX) and value != default:
            out.append((path, value))
    return out


def ignored_note(scene: dict, name: Callable[[str], str] = str) -> str | None:
    """One line saying which photometric fields a paper-mode ``scene`` ignores (None when none),
    with ``name`` turning a field's path into the reader's words (the panel's, in Blender)."""
    fields = ignored_fields(scene)
    if not fields:
        return None
    named = ", ".join(f"{name(path)} = {show_value(value)}" for path, value in fields[:_NAMED_AT_MOST])
    more = f" and {len(fields) - _NAMED_AT_MOST} more" if len(fields) > _NAMED_AT_MOST else ""
    return (f"the paper light model ignores photometric fields: {named}{more}; "
            f'they take effect with {name("light_model")} "photometric"')


def _leaves(doc: dict, section: S.Section, path: str):
    """``(path, value)`` of every leaf field of a normalised ``doc`` below ``section``."""
    for key, spec in section.fields.items():
        if key not in doc:
            continue
        where = f"{path}{key}"
        if isinstance(spec, S.Section):
            yield from _leaves(doc[key], spec, where + ".")
        elif isinstance(spec, S.ListOf):
            for i, item in enumerate(doc[key]):
                yield from _leaves(item, spec.item, f"{where}[{i}].")
        else:
            yield where, doc[key]
