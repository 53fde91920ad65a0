"""The 3D View framed on the lamp, and the startup Cube named, never hidden silently
(``lamp_addon.design.view_frame``).

In Blender's startup file the lamp is built at the origin inside the 2 m Cube. The first lamp frames
the 3D Views on the design as View Selected does (checked through each region's own matrices: the
design's box projects inside the region), names the Cube that encloses it in one line, and leaves the
Cube as it was; Hide Other Objects hides the others in the viewport as one undo step.
"""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.blender


def _inside_every_view(lamp_addon, bl_scene) -> list[tuple[str, float]]:
    """(area, reach) per 3D View of the windows: the largest |x|, |y| of the design's box corners in the
    region's normalised device coordinates (inside the region below 1), through the region's own
    projection matrix (Blender's ``window_matrix``) and its view matrix."""
    corners = lamp_addon.design.view_frame.design_corners(bl_scene)
    reaches = []
    for area, _region, view in lamp_addon.design.view_frame.views_of(bl_scene):
        to_clip = view.window_matrix @ lamp_addon.design.view_frame.view_matrix(view)
        reach = 0.0
        for corner in corners:
            x, y, _, w = to_clip @ corner.to_4d()
            assert w > 0.0  # in front of the eye
            reach = max(reach, abs(x / w), abs(y / w))
        reaches.append((area.ui_type, reach))
    return reaches


def test_the_view_matrix_is_blenders(lamp_addon, startup_scene):
    """The view matrix computed from the view's centre, rotation and distance is the one Blender drew
    the startup file's 3D View with (to its stored single precision)."""
    for _, _, view in lamp_addon.design.view_frame.views_of(startup_scene):
        ours = lamp_addon.design.view_frame.view_matrix(view)
        scale = view.view_distance
        assert max(abs(a - b) for ra, rb in zip(ours, view.view_matrix, strict=True)
                   for a, b in zip(ra, rb, strict=True)) < 1e-3 * scale


def _cube_state(ob) -> tuple:
    return tuple(ob.location), tuple(ob.scale), ob.hide_get(), ob.hide_viewport, ob.hide_render


def test_the_first_lamp_frames_the_3d_view_and_names_the_cube(lamp_addon, startup_scene, capfd):
    import bpy

    views = lamp_addon.design.view_frame.views_of(startup_scene)
    assert views  # the startup file's Layout has a 3D View, under xvfb-run as on a desktop
    before = {id(v): (tuple(v.view_location), v.view_distance) for _, _, v in views}
    reach_before = dict(_inside_every_view(lamp_addon, startup_scene))
    cube = startup_scene.objects["Cube"]
    cube_before = _cube_state(cube)
    capfd.readouterr()
    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    said = capfd.readouterr().out
    reaches = _inside_every_view(lamp_addon, startup_scene)
    print(f"\nbefore: {reach_before}\nafter: {reaches}")
    assert reaches and all(0.5 < reach < 1.0 for _, reach in reaches)  # inside, and filling most of it
    assert any(before[id(v)] != (tuple(v.view_location), v.view_distance) for _, _, v in views)
    assert 'it is inside "Cube": Hide Other Objects shows it' in said
    assert _cube_state(cube) == cube_before  # nothing of the user's hidden or moved

    assert bpy.ops.lamp.hide_others() == {"FINISHED"}
    assert cube.hide_get() and startup_scene.objects["Light"].hide_get()
    assert not cube.hide_render  # renders unchanged
    bpy.ops.ed.undo_push(message="after hide")
    assert lamp_addon.design.view_frame.enclosing(startup_scene) == []


def test_hide_other_objects_is_one_undo_step_and_alt_h_shows_them(lamp_addon, startup_scene):
    import bpy

    assert bpy.types.LAMP_OT_hide_others.bl_options == {"REGISTER", "UNDO"}  # headless Blender has no undo stack
    assert bpy.ops.lamp.hide_others() == {"FINISHED"}
    others = [ob for ob in startup_scene.objects if not lamp_addon.design.view_frame.is_lamp_object(ob)]
    assert others and all(ob.hide_get() for ob in others)
    assert not bpy.ops.lamp.hide_others.poll()  # only the lamp is visible now
    window = bpy.context.window
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    with bpy.context.temp_override(window=window, area=area, region=region):
        assert bpy.ops.object.hide_view_clear() == {"FINISHED"}  # Alt+H in the 3D View
    assert not any(ob.hide_get() for ob in others)


def test_frame_lamp_frames_the_3d_view_on_a_moved_lamp(lamp_addon, startup_scene):
    import bpy

    assert bpy.ops.lamp.lamp_add() == {"FINISHED"}
    assert bpy.ops.lamp.build() == {"FINISHED"}
    root = lamp_addon.design.root.find_root(startup_scene)
    root.location = (3.0, 2.0, 1.0)
    for _, _, view in lamp_addon.design.view_frame.views_of(startup_scene):
        view.view_location, view.view_distance = (-5.0, 0.0, 0.0), 30.0  # the user looked elsewhere
    startup_scene.view_layers[0].update()
    assert bpy.ops.lamp.frame_design() == {"FINISHED"}
    assert all(0.5 < reach < 1.0 for _, reach in _inside_every_view(lamp_addon, startup_scene))
