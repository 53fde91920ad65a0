"""What the study operators and the Study panel share, below both: the settings turned into a study,
the contact-sheet image and the last study it holds.

``study_panel`` draws the settings (``Scene.lamp_study``) and ``study_ops`` runs them; both import this
module and neither imports the other, so no import circle is possible.
"""

from __future__ import annotations

import bpy

from ..core_tracer.scene import spec as S
from ..core_tracer.scene.validate import SceneError
from ..core_tracer.study import definition as st
from . import design_properties, render_camera

ALL_LAMPS = "ALL"
SHEET_IMAGE = "Lamp Study"
STUDY_PROPERTY = "lamp_study"  # custom property of the sheet image: the study's JSON, so it can be re-run

_cache: dict[str, object] = {"json": None, "study": None}  # the last sheet's study, parsed once


def is_single_number(path: str) -> bool:
    spec = S.lookup(path)
    return isinstance(spec, S.Num) and spec.size == 1


def is_lamp_parameter(path: str) -> bool:
    return path.split(".")[0] in S.LAMP.fields


def axis_doc(axis) -> dict:
    """One axis of the settings as a ``lamp-study/1`` axis document (checked when the study is built)."""
    path = axis.parameter
    if axis.lamp != ALL_LAMPS and is_lamp_parameter(path):
        path = f"lamps[{axis.lamp}].{path}"
    if axis.mode == "RANGE":
        if not is_single_number(axis.parameter):
            raise SceneError(path, "is a vector or a switch; give its values as a list (e.g. 0.9/0.1/0.1, 0.5/0.5/0.5)")
        return {"parameter": path, "range": [axis.start, axis.stop], "steps": axis.steps}
    if not axis.values.strip():
        raise SceneError(path, "has no values; write them separated by commas")
    return st.parse_vary(f"{path}={axis.values}")


def study_from_settings(bl_scene) -> st.Study:
    """The study the settings describe, of the scene's current design seen through its camera.
    Raises ``SceneError`` (with the parameter, value and range) for a bad setting or design."""
    settings = bl_scene.lamp_study
    size = (settings.width, settings.height)
    if bl_scene.camera is not None:
        base = render_camera.scene_for_render(bl_scene, size=size)
    else:  # no scene camera: the design's own camera section
        base = design_properties.design_to_scene(bl_scene)
        base["image"] = {"width": size[0], "height": size[1]}
    axes = [axis_doc(settings.axis_1)]
    if settings.use_axis_2:
        axes.append(axis_doc(settings.axis_2))
    return st.Study.build(base, axes, size)


# ---------------------------------------------------------------------------------------------
# The sheet image and its study


def sheet_image() -> bpy.types.Image | None:
    return bpy.data.images.get(SHEET_IMAGE)


def last_study() -> st.Study | None:
    """The study of the "Lamp Study" image (parsed once per study, then cached)."""
    image = sheet_image()
    text = image.get(STUDY_PROPERTY) if image is not None else None
    if not isinstance(text, str):
        return None
    if _cache["json"] != text:
        try:
            study = st.Study.from_json(text, STUDY_PROPERTY)
        except SceneError:
            study = None
        _cache.update(json=text, study=study)
    return _cache["study"]  # type: ignore[return-value]


def remember_study(study: st.Study, text: str) -> None:
    """Cache the study whose JSON ``text`` the sheet image now holds."""
    _cache.update(json=text, study=study)


def register() -> None:
    pass  # nothing to register yet: listed in ``modules()`` for its ``unregister``


def unregister() -> None:
    _cache.update(json=None, study=None)  # the cached study belongs to this registration
