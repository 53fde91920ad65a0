"""Where a new lamp goes: Add Lamp keeps a valid design valid.

The new lamp is a copy of the active one (the spec's default lamp in an empty design), placed right
of the others with a small margin, and the body grows to hold it. A result that is not a valid
design (a body wider than the spec allows) raises ``SceneError`` naming the field and its range.
"""

from __future__ import annotations

import copy

from ...core_tracer.scene import spec
from ...core_tracer.scene.derived import new_lamp
from ...core_tracer.scene.outline import Outline
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import parse_scene

MARGIN_MM = 5.0  # between a new lens and its neighbour, and at least between it and the body's edge
IMAGE_LONGER_SIDE = 512  # px: a new design's image, its longer side
IMAGE_MARGIN = 0.1  # of the body's larger side, around the body, in the image a new design gets


def image_size_for_body(body_size, longer: int = IMAGE_LONGER_SIDE, margin: float = IMAGE_MARGIN) -> tuple[int, int]:
    """The image a new design gets: the body's aspect with a margin around it (a 480 x 120 mm body:
    512 x 192 px), so that the body fills the frame instead of a band of a square. Even sizes, the
    longer side ``longer``."""
    width, height = (float(v) for v in body_size)
    pad = 2.0 * margin * max(width, height)
    aspect = (width + pad) / (height + pad)
    if aspect >= 1.0:
        return longer, max(2, 2 * round(longer / aspect / 2))
    return max(2, 2 * round(longer * aspect / 2)), longer


def design_with_new_lamp(doc: dict, active_index: int) -> dict:
    """A copy of the design document ``doc`` with a lamp added by ``place_new_lamp``: a copy of
    the active lamp (so its lens radius, and a reflector and bulb that fit that lens), or the
    spec's default lamp in an empty design. Raises ``SceneError`` (field and allowed range) when
    the result is not a valid design, checked as ``parse_scene`` does, camera aside (a new lamp
    does not change what the camera may be)."""
    doc = with_new_lamp_unchecked(doc, active_index)
    parse_scene({key: value for key, value in doc.items() if key != "camera"})
    return doc


def refusal_of_new_lamp(doc: dict, active_index: int) -> str | None:
    """Why Add Lamp cannot add a lamp to ``doc``, or None. Only the new lamp's own place is a
    reason: an error the design has anyway is the panel's to show and does not block adding."""
    try:
        parse_scene({key: value for key, value in doc.items() if key != "camera"})
    except SceneError:
        body = with_new_lamp_unchecked(doc, active_index)["body"]
        limit = spec.BODY.fields["size"].hi
        if max(body["size"]) > limit:
            return (f"Cannot add a lamp: the body would need {max(body['size']):g} mm; body.size allows up "
                    f"to {limit:g} mm (make the lenses smaller or remove a lamp)")
        return None
    try:
        design_with_new_lamp(doc, active_index)
    except SceneError as e:
        return f"Cannot add a lamp: {e}"
    return None


def with_new_lamp_unchecked(doc: dict, active_index: int) -> dict:
    """A copy of ``doc`` with a copy of the active lamp (the spec's default lamp, in the preferred
    forms, in an empty design) placed beside the others; not checked."""
    doc = copy.deepcopy(doc)
    lamps = doc["lamps"]
    lamps.append(copy.deepcopy(lamps[active_index]) if 0 <= active_index < len(lamps) else new_lamp())
    place_new_lamp(doc)
    return doc


def place_new_lamp(doc: dict, margin: float = MARGIN_MM) -> None:
    """Place the last lamp of the design document ``doc`` and make the body hold it (in place).

    The new lens goes ``margin`` to the right of the rightmost lens, at its own height ``center[1]``
    (the first lamp at the body's centre). The body keeps its other edges and grows on each side the
    new lens needs, leaving beside it the free border the body has left of its leftmost lens (at
    least ``margin``), so the body's centre moves as it grows."""
    *others, new = doc["lamps"]
    half_w, half_h = _half_size(new)
    body = doc["body"]
    (bx, bz), (width, height) = body["center"], body["size"]
    left, right, bottom, top = bx - width / 2, bx + width / 2, bz - height / 2, bz + height / 2
    if others:
        x = max(o["center"][0] + _half_size(o)[0] for o in others) + margin + half_w
        z = new["center"][1]
        border = max(margin, min(o["center"][0] - _half_size(o)[0] for o in others) - left)
    else:
        x, z, border = bx, bz, margin
    new["center"] = [x, z]
    left, right = min(left, x - half_w - border), max(right, x + half_w + border)
    bottom, top = min(bottom, z - half_h - margin), max(top, z + half_h + margin)
    body["center"] = [(left + right) / 2, (bottom + top) / 2]
    body["size"] = [right - left, top - bottom]


def _half_size(lamp: dict) -> tuple[float, float]:
    """Half the width and height of a lamp's lens outline (its radius twice for a round lens)."""
    outline = Outline.of_lens(lamp["lens"])
    return outline.half_w, outline.half_h
