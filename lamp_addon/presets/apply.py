# SPDX-License-Identifier: GPL-3.0-or-later
"""What applying a preset does to the Blender scene, and the view a saved preset records.

A preset is applied only after it has been read again and validated in full, and then all at once
(``design.properties.scene_to_design``); ``apply_preset_whole`` puts the scene back as it was
(``state.SceneState``) when anything fails part-way. Applying shows the preset's view through the
add-on's own "Lamp Camera" (created when the scene has no camera); a camera of the designer's own is
never moved. The operators that call these are in ``ops``.
"""

from __future__ import annotations

import struct
from typing import NamedTuple

import bpy

from ...core_tracer.raytrace import environment
from ...core_tracer.scene.beside import environment_file
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import normalize
from ..design import builder as design_builder
from ..design import camera as render_camera
from ..design import curves as design_curves
from ..design import lamp_camera
from ..design import properties as design_properties
from ..design import root as design_root
from ..design import setup as render_setup
from ..design import validity as design_validity
from ..freeform import loading as freeform_loading
from ..freeform import parametric as freeform_parametric
from .state import SceneState

# ---------------------------------------------------------------------------------------------
# The view a preset records and shows


def _as_stored(value):
    """A camera value as the design's 32-bit float properties keep it, so that applying the preset
    gives back exactly the numbers it holds (``design.properties.from_float32``)."""
    if isinstance(value, dict):
        return {k: _as_stored(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_as_stored(v) for v in value]
    if isinstance(value, float):
        return design_properties.from_float32(struct.unpack("<f", struct.pack("<f", value))[0])
    return value


def design_as_seen(bl_scene: bpy.types.Scene) -> dict:
    """The design as a preset records it: seen through the Blender scene camera at the render size
    when the scene has a camera, else through the design's own camera. Raises ``SceneError``.

    A scene camera that shows the design's own view (say, right after applying a preset) keeps the
    design's numbers, free of Blender's single-precision noise.
    """
    if bl_scene.camera is None:
        return design_properties.design_to_scene(bl_scene)
    seen = render_camera.scene_for_render(bl_scene)
    try:
        own = design_properties.design_to_scene(bl_scene)["camera"]
    except SceneError:
        own = None  # the design's own camera section does not hold a valid view: the scene camera is the view
    same = own is not None and render_camera.same_view(seen["camera"], own)
    seen["camera"] = own if same else _as_stored(seen["camera"])
    return normalize(seen)


def show_view(bl_scene: bpy.types.Scene, scene: dict) -> render_setup.News | None:
    """Show the design's view (just set from a preset) through the add-on's Lamp Camera.

    The design's camera fields are the Lamp Camera (``design.view_link.sync_view``): it takes the
    preset's view, made when the scene has none, and is framed on the body from that view's direction
    when the view does not show the whole body, as the first lamp of a file does (so a preset is
    framed the same whatever was applied before). A camera of the designer's stays as it is.
    Returns what happened, for the report."""
    mine = bl_scene.camera is not None and not render_camera.is_lamp_camera(bl_scene.camera)
    if mine and render_camera.find_lamp_camera(bl_scene) is None:
        return render_setup.News(f'your camera "{bl_scene.camera.name}" kept',
                                 f'Kept your camera "{bl_scene.camera.name}": the preset\'s view is the design\'s '
                                 "camera; Frame Lamp makes the Lamp Camera")
    ob, made = lamp_camera.ensure_lamp_camera(bl_scene, frame=False)
    if not render_setup.design_view_shows_body(bl_scene) and ob.data.type in {"PERSP", "ORTHO"}:
        lamp_camera.frame_on_body(bl_scene, ob, render_camera.scene_camera_to_dict(bl_scene, ob))
    if mine:
        return render_setup.News(f'your camera "{bl_scene.camera.name}" kept',
                                 f'Kept your camera "{bl_scene.camera.name}": the preset\'s view is on '
                                 f'"{ob.name}"; Frame Lamp makes it the scene camera')
    return render_setup.News("", made[:1].upper() + made[1:] if made else f'Moved "{ob.name}" to the preset\'s view')


class Applied(NamedTuple):
    """What applying a preset did: a short clause for the report's one line, the rest for the Info editor."""

    short: str
    details: list[str]


def apply_preset(bl_scene: bpy.types.Scene, scene: dict, path: str | None = None) -> Applied:
    """Set the design from a preset, all or nothing, then show its view (``show_view``) and, when the
    lamp has been built in this scene, rebuild it so that its objects are the preset's too. A free-form
    preset (read from ``path``) also brings its parts in as objects with roles (``freeform.loading``),
    its meshes read and checked first. In a file not yet set up for the lamp (Auto Build on, nothing
    built) the scene is set up as the first Add Lamp does, and the preset's view shown by that set-up.
    Returns what happened, for the report."""
    parts = None
    if path is not None and scene["environment"]["world"] == "file":
        # The image beside the preset (refused when it leads elsewhere), held in the design by its path.
        scene = {**scene, "environment": {**scene["environment"], "file": environment_file(path, scene["environment"])}}
    # The image's header counted as the tracer counts it (one that declares more than the budget
    # is refused here, before any change), never its pixels: they are read when a render needs them.
    environment.world_bytes(scene)
    if "freeform" in scene:
        if path is None:
            raise SceneError("freeform", "a free-form design needs its file, to find its .glb beside it")
        parts = freeform_loading.read_parts(path, scene)  # before any change: all or nothing
    design_properties.scene_to_design(bl_scene, scene)
    if path is not None:  # its measured curves (.csv) are found beside it (design.curves)
        design_curves.remember_preset_folder(bl_scene, path)
    design = design_properties.design_to_scene(bl_scene)
    built = any(ob.get(design_root.PART_KEY) for ob in bl_scene.objects)
    first = not built and bl_scene.lamp_design.auto_build and not render_setup.is_set_up(bl_scene)
    # Auto Build makes the lamp in a moment: its first build in this file, so the scene is set up now
    # (the Lamp Camera at the preset's view, Lamp Tracer, the exposure once), as the first Add Lamp does.
    # The exposure of the preset's light model first, said in the report (an edit's listener would set it unsaid).
    news = [render_setup.follow_light_model(bl_scene, design)]
    news += [] if first else [show_view(bl_scene, design)]
    if parts is not None:
        made = freeform_loading.make_parts(bl_scene, scene, parts)
        news.append(render_setup.News(f"{len(made)} free-form parts", f"Made {len(made)} free-form parts"))
    if first:
        news += render_setup.set_up(bl_scene)
    if parts is not None:
        # The preset's meshes are the whole lamp: its parametric lamps are built now (not later by Auto
        # Build) and hidden from view and renders, as Convert to Free-form leaves them, so the tracer does
        # not meet the same lens twice.
        design_builder.build_lamp(bl_scene, design)
        hidden = freeform_parametric.used_parts(bl_scene, None)
        for ob in hidden:
            ob.hide_set(True)
            ob.hide_render = True
        news.append(render_setup.News("", f"Hid the {len(hidden)} parametric parts the free-form parts stand in for"))
    elif built:
        design_builder.build_lamp(bl_scene, design)
        news.append(render_setup.News("", "Rebuilt the lamp objects"))
    news = [n for n in news if n is not None]
    return Applied(render_setup.news_text(news), render_setup.news_details(news))


def apply_preset_whole(bl_scene: bpy.types.Scene, scene: dict, path: str | None = None) -> str:
    """``apply_preset``, all or nothing: whatever fails part-way (a ``SceneError``, or a failure of
    a file or of Blender), the scene is put back as it was (``state``) and the error raised
    again; the operator's one undo step then holds no change."""
    before = SceneState(bl_scene)
    try:
        applied = apply_preset(bl_scene, scene, path)
    except Exception:
        before.restore(bl_scene)
        raise
    design_validity.remember(bl_scene)
    return applied
