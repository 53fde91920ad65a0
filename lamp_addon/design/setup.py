"""What a file needs to show the lamp, done once when the lamp is first built there.

A designer who builds a lamp in Blender's startup file expects to see it: the startup Camera is
11 m away and frames the Cube, the render engine is EEVEE, and at exposure 0 a lit lens (ten or
more times display white) is a flat pale disk under AgX. So the first build of a design in a file
(``set_up``) sets the scene up for the lamp, each change said in the operator's report:

- **camera**: the add-on's Lamp Camera (made when missing, at the design's view, framed on the
  body when that view does not show it all) becomes the scene camera, parented to the design's
  root so that it moves with the lamp. The user's own camera object is never touched; it is only
  no longer the scene camera (the Scene properties switch back).
- **engine**: Lamp Tracer, when the scene still renders with EEVEE (the engine of a new file): F12
  and the viewport's Rendered shading then show the paper's model. Another engine is a choice.
- **exposure**: the exposure belongs to the view, not to the design. The first lamp of a new file
  sets the scene's exposure (Color Management) once, to the design's automatic exposure measured
  with its bulbs on (``design_exposure_lit``: a design whose bulbs are all off, "Paper study: lamp
  off" say, is exposed for the lamp lit, so the lit design applied next is not washed out), when
  the exposure is still the default 0. After that neither Build Lamp nor Apply Preset changes it,
  so a stop lamp looks brighter than a tail lamp; *Exposure from Design* is the explicit way to
  expose for the design again. The paper and photometric models' images differ in scale (the
  photometric one is already exposed by its EV100), so each light model keeps its own exposure
  (``follow_light_model``): switching model sets the new model's, and the old one's is kept.
- **view transform**: when the scene still shows through Blender's default view (AgX, no look),
  the lamp view (``display.LAMP_VIEW``, Filmic), under which lit red and amber lamps keep their
  hue (AgX washes them to salmon and peach). A view or look the user chose is theirs: kept.
- **views**: the 3D Views are framed on the lamp (``view_frame``), and an object of the user's that
  encloses it (the startup Cube) is named in the report, never hidden or moved.

The scene remembers that it was set up (``SETUP_KEY``), so a camera or an engine the user chose
afterwards is never changed again by a build.
"""

from __future__ import annotations

import json
from typing import NamedTuple

from ...core_tracer.images import display
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.scene.validate import parse_scene
from .. import image_view
from ..convert import camera as cm
from . import camera, lamp_camera, view_frame
from . import properties as design_properties

ENGINE_ID = "LAMP_TRACER"  # the Lamp Tracer's RenderEngine (``render.engine``), which a file set up renders with

# scene custom property: JSON {"exposure": the value the add-on set, or null, "model": the light model
# last seen, "exposures": {light model: the exposure kept for it}}
SETUP_KEY = "lamp_scene_setup"
DEFAULT_ENGINES = ("BLENDER_EEVEE", "BLENDER_EEVEE_NEXT")  # what a new file renders with (4.2-5.0)
EXPOSURE_TOLERANCE = 1e-3  # stops: Blender stores the exposure in single precision


def _memory(bl_scene) -> dict | None:
    text = bl_scene.get(SETUP_KEY)
    if not isinstance(text, str):
        return None
    try:
        memory = json.loads(text)
    except ValueError:
        return None
    return memory if isinstance(memory, dict) else None


def _remember(bl_scene, exposure: float | None) -> None:
    """Remember that the scene is set up, under its design's light model, with the exposure the
    add-on set for that model (None: the user's own, kept)."""
    memory = _memory(bl_scene) or {}
    model = bl_scene.lamp_design.light_model
    exposures = _exposures(memory)
    if exposure is not None:
        exposures[model] = exposure
    bl_scene[SETUP_KEY] = json.dumps({"exposure": exposure, "model": model, "exposures": exposures})


def _exposures(memory: dict) -> dict[str, float]:
    """The exposure kept for each light model (none in a file set up before there were two)."""
    kept = memory.get("exposures")
    if not isinstance(kept, dict):
        return {}
    return {model: float(x) for model, x in kept.items() if isinstance(x, int | float) and not isinstance(x, bool)}


def follow_light_model(bl_scene, design: dict | None = None) -> News | None:
    """One exposure per light model: when the design's light model changed since the scene was last
    seen, the scene's exposure is kept as the old model's and the new model's is set, the one kept
    for it or, the first time, its automatic exposure (``design_exposure_lit``: 0 EV for a
    photometric design, whose EV100 already puts display white at 1; a paper design's measured). A
    paper design exposed at -4 EV made the first photometric F12 nearly black; the two models' images
    differ in scale, so one exposure cannot serve both. Nothing happens in a scene not set up yet
    (its first build exposes it) or while the design is invalid (tried again at the next edit).
    A paper design is measured as ``design`` (a normalised scene: a preset's own view) or, without
    it, through the scene camera. Returns what changed, for a report."""
    memory = _memory(bl_scene)
    model = bl_scene.lamp_design.light_model
    if memory is None:
        return None
    before = memory.get("model")
    if before == model:
        return None
    exposures = _exposures(memory)
    if before is not None:
        exposures[before] = bl_scene.view_settings.exposure
    exposure = exposures.get(model)
    if exposure is None and before is not None:
        try:
            exposure = design_exposure_lit(design if design is not None else camera.scene_for_render(bl_scene))
        except SceneError:
            return None  # not measurable now: the panel says why; the next edit tries again
    if exposure is not None:
        bl_scene.view_settings.exposure = exposure
    bl_scene[SETUP_KEY] = json.dumps({**memory, "model": model, "exposures": exposures | (
        {model: exposure} if exposure is not None else {})})
    if before is None:
        return None  # a file set up before there were two exposures: its exposure is this model's
    return News(f"{exposure:+.1f} EV for the {model} model",
                f"Exposure {exposure:+.1f} EV, the {model} model's; the {before} model's "
                f"{exposures[before]:+.1f} EV is kept for it")


def light_model_edited(bl_scene) -> None:
    """A design edit (``design.properties.EDIT_LISTENERS``): the exposure follows a change of light
    model at once (the Light panel says which exposure is the model's). A preset being written is
    left to Apply Preset, which follows it once the whole design is written and reports it."""
    if not design_properties.is_writing():
        follow_light_model(bl_scene)


def kept_exposure_text(bl_scene) -> str | None:
    """What the Light panel says under the light model when another model keeps its own exposure:
    "Exposure +0.0 EV for this model (paper: -3.9 EV)"."""
    memory = _memory(bl_scene)
    model = bl_scene.lamp_design.light_model
    if memory is None or memory.get("model") != model:
        return None
    others = {m: x for m, x in _exposures(memory).items() if m != model}
    if not others:
        return None
    kept = ", ".join(f"{m}: {x:+.1f} EV" for m, x in sorted(others.items()))
    return f"Exposure {bl_scene.view_settings.exposure:+.1f} EV for this model ({kept})"


def is_set_up(bl_scene) -> bool:
    """Whether the scene was set up for the lamp (by a build, or Exposure from Design)."""
    return _memory(bl_scene) is not None


def design_view_shows_body(bl_scene) -> bool:
    """Whether the design's own camera is a valid view in which the whole body lies in the image."""
    doc = design_properties.design_document(bl_scene)
    try:
        scene = parse_scene({**doc, "lamps": doc["lamps"] or [{}]})
    except SceneError:
        return False
    size = (scene["image"]["width"], scene["image"]["height"])
    corners = cm.project(scene["camera"], size, cm.box_corners(*cm.body_box(scene)))
    return all(0.0 <= x <= size[0] and 0.0 <= y <= size[1] and depth > 0.0 for x, y, depth in corners)


class News(NamedTuple):
    """One change the set-up made: a few words for the report's one line, and the whole of it for the
    Info editor."""

    short: str
    detail: str
    lead: bool = False  # said first: what the user must do to see the lamp


def _camera(bl_scene) -> News | None:
    previous = bl_scene.camera
    if camera.find_lamp_camera(bl_scene) is None:
        ob, what = lamp_camera.ensure_lamp_camera(bl_scene, frame=not design_view_shows_body(bl_scene))
    else:  # made earlier (by a preset, by Compare): the link renewed
        ob, what = lamp_camera.ensure_lamp_camera(bl_scene)[0], ""
        if previous is not ob:
            bl_scene.camera = ob
            what = f'made "{ob.name}" the scene camera' + (
                f' (your "{previous.name}" is kept as it was)' if previous is not None else "")
    lamp_camera.carry_with_root(bl_scene, ob)  # the lamp's view moves with the lamp
    return News(f'"{ob.name}"', what[:1].upper() + what[1:]) if what else None


def _engine(bl_scene) -> News | None:
    engine = bl_scene.render.engine
    if engine not in DEFAULT_ENGINES:
        return None
    bl_scene.render.engine = ENGINE_ID
    return News("Lamp Tracer", "Render engine Lamp Tracer (was EEVEE): F12 and Rendered shading show the lamp")


def is_lit(scene: dict) -> bool:
    """Whether anything in a normalised design gives light: a bulb that is on (a parametric lamp's or
    a free-form bulb's)."""
    bulbs = [lamp["bulb"] for lamp in scene["lamps"]]
    bulbs += [part["bulb"] for part in scene.get("freeform", {}).get("parts", []) if part["role"] == "bulb"]
    return any(bulb["on"] for bulb in bulbs)


def lit_version(scene: dict) -> dict:
    """The design with every bulb on: what its exposure is measured on when nothing is lit."""
    lamps = [{**lamp, "bulb": {**lamp["bulb"], "on": True}} for lamp in scene["lamps"]]
    lit = {**scene, "lamps": lamps}
    if "freeform" in scene:
        parts = [{**part, "bulb": {**part["bulb"], "on": True}} if part["role"] == "bulb" else part
                 for part in scene["freeform"]["parts"]]
        lit["freeform"] = {**scene["freeform"], "parts": parts}
    return lit


def design_exposure_lit(scene: dict) -> float:
    """The design's automatic exposure (``image_view.design_exposure``), measured with its bulbs on."""
    return image_view.design_exposure(scene if is_lit(scene) else lit_version(scene))


def set_design_exposure(bl_scene) -> tuple[float, bool]:
    """Set the scene's exposure to the design's automatic exposure seen through the scene camera, measured
    with the bulbs on (``design_exposure_lit``). Returns (the exposure, whether anything is lit).
    Raises ``SceneError`` (no camera, an invalid design)."""
    scene = camera.scene_for_render(bl_scene)
    exposure = design_exposure_lit(scene)
    bl_scene.view_settings.exposure = exposure
    _remember(bl_scene, exposure)
    return exposure, is_lit(scene)


def _first_exposure(bl_scene) -> News | None:
    """The exposure of a new file's first lamp, set once when the scene's is still the default 0 (one
    the user set before is theirs)."""
    settings = bl_scene.view_settings
    if abs(settings.exposure) > EXPOSURE_TOLERANCE:
        return None
    try:
        exposure, lit = set_design_exposure(bl_scene)
    except SceneError:
        # No camera, an invalid design, or surroundings the tracer refuses to read (an image whose
        # header declares too much): the operator, the panel or the build's report says why.
        return None
    return News(f"{exposure:+.1f} EV",
                f"Exposure {exposure:+.1f} EV ({settings.view_transform}), the design's"
                + ("" if lit else " with its bulbs on") + ": the lit lens shows its cut pattern. Build Lamp "
                "and Apply Preset keep it; Exposure from Design exposes again")


BLENDER_DEFAULT_VIEW = ("AgX", "None")  # a new file's view transform and look (Blender 4.0-5.0)


def _first_view(bl_scene) -> News | None:
    """The lamp view for a new file's first lamp, when the scene still has Blender's default view."""
    settings = bl_scene.view_settings
    if (settings.view_transform, settings.look) != BLENDER_DEFAULT_VIEW:
        return None
    try:
        settings.view_transform = display.LAMP_VIEW
    except TypeError:  # a colour configuration without it: keep Blender's
        return None
    return News(display.LAMP_VIEW,
                f"View transform {display.LAMP_VIEW} (was AgX, Blender's default): lit red and amber lamps keep "
                "their hue. Render Properties > Color Management changes it back")


def _views(bl_scene) -> News | None:
    """The 3D Views framed on the design, and an object of the user's that hides it named."""
    framed = view_frame.frame_views(bl_scene)
    hidden = view_frame.enclosing(bl_scene)
    if hidden:
        return News(f'it is inside "{hidden[0]}": Hide Other Objects shows it',
                    f'The lamp is inside "{hidden[0]}" (yours, not moved): Hide Other Objects (Lamp tab) hides '
                    "the other objects in the viewport; Alt+H shows them again", lead=True)
    return News("", f"Framed {framed} 3D Views on the lamp") if framed else None


def set_up(bl_scene) -> list[News]:
    """Set the scene up for the lamp after its first build or first lamp (see the module's doc): the
    camera, the engine and the exposure, once, and the 3D Views framed on it. Returns what changed,
    for the operator's report (``news_text``, ``news_details``)."""
    news = []
    if not is_set_up(bl_scene):
        news += [_camera(bl_scene), _engine(bl_scene), _first_view(bl_scene), _first_exposure(bl_scene),
                 _views(bl_scene)]
        if not is_set_up(bl_scene):
            _remember(bl_scene, None)  # the user's own exposure, or none measured: kept as it is
    ob = camera.find_lamp_camera(bl_scene)
    if ob is not None:
        lamp_camera.carry_with_root(bl_scene, ob)  # made before the root (Add Lamp, a preset)
    return [n for n in news if n is not None]


def news_text(news: list[News]) -> str:
    """The changes as short clauses of a report: "; it is inside ...; set up "Lamp Camera", Lamp Tracer,
    -3.9 EV" ("" for none)."""
    leads = [n.short for n in news if n.short and n.lead]
    others = [n.short for n in news if n.short and not n.lead]
    return "".join(f"; {text}" for text in leads) + ("; set up " + ", ".join(others) if others else "")


def news_details(news: list[News]) -> list[str]:
    """The changes in full, for the Info editor."""
    return [n.detail for n in news]
