"""The CLI's commands, one module each (see ``cli.COMMANDS``), and what they share."""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
import threading
from collections.abc import Iterator

from ..fileio import check_writable
from ..images import display
from ..scene import spec as S
from ..scene.beside import environment_file, with_spectrum_files
from ..scene.light_models import ignored_note
from ..scene.messages import show_value
from ..scene.reading import SceneError, read_json
from ..scene.safe_text import printable
from ..scene.validate import parse_scene


def in_file(error: SceneError, file: str | os.PathLike) -> SceneError:
    """The same error, prefixed with the file it came from (once)."""
    name = os.fspath(file)
    if error.path == name or error.path.startswith(name + ":"):
        return error
    return SceneError(f"{name}: {error.path}" if error.path else name, error.message)


def check_image_side(option: str, value: int | None, field: str = "width") -> None:
    """``--width``/``--height``/``--samples`` follow the same range as ``image.width``/``height``/``samples``."""
    if value is None:
        return
    side = S.IMAGE.fields[field]
    if not side.lo <= value <= side.hi:
        raise SceneError(option, f"{show_value(value)} is out of range; allowed {side.range_text()}")


def load_scene_file(path: str | os.PathLike, width: int | None = None, height: int | None = None,
                    samples: int | None = None) -> dict:
    """Read and validate a scene file, with the image size and samples optionally overridden.

    The override goes into the document before validation, so a default camera frames the body
    for the image actually rendered and the stored scene says what was rendered.
    """
    check_image_side("--width", width)
    check_image_side("--height", height)
    check_image_side("--samples", samples, "samples")
    doc = read_json(path)
    if isinstance(doc, dict) and (width or height or samples):
        image = doc.get("image", {})
        if isinstance(image, dict):
            image = dict(image)
            if width:
                image["width"] = width
            if height:
                image["height"] = height
            if samples:
                image["samples"] = samples
            doc["image"] = image
    try:
        scene = parse_scene(doc)
        environment_file(path, scene["environment"])  # beside the file, or refused
        if scene.get("light_model") == "photometric":  # what the render computes from the spectra (issue 33)
            from ..raytrace import spectral
            from ..scene.beside import with_spectrum_files

            spectral.check_lamps(with_spectrum_files(path, scene))
    except SceneError as e:
        raise in_file(e, path) from None
    traced_scene(path, scene)  # the measured curves it names are beside it, or refused
    note = ignored_note(scene)
    if note:  # reported, not refused: the fields are kept for a switch to the photometric model
        print(f"note: {printable(os.fspath(path))}: {note}", file=sys.stderr)
    return scene


def traced_scene(path: str | os.PathLike, scene: dict) -> dict:
    """The scene loaded from ``path`` as the tracer takes it: the measured curves it names
    (``filter_file``, ``spectrum_file``) by their full paths beside the file, confined to its folder
    (``scene.beside``). The files written keep the plain names (``scene`` itself)."""
    try:
        return with_spectrum_files(path, scene)
    except SceneError as e:
        raise in_file(e, path) from None


def design_meshes(path: str | os.PathLike, scene: dict):
    """The meshes of a free-form design beside ``path``, their geometry checked before any render
    (the meshes, their roles, the lens volumes) in a ``freeform.design.DesignMeshes`` that every
    render of them shares; None for a parametric design."""
    if "freeform" not in scene:
        return None
    # free-form only: the mesh modules load when a design has meshes (start-up speed)
    from ..freeform import available
    from ..freeform.design import DesignMeshes
    from ..freeform.loading import load_meshes

    ok, reason = available()
    if not ok:
        raise SceneError(printable(os.fspath(path)), reason)
    meshes = DesignMeshes(load_meshes(path, scene))
    try:
        meshes.cache.get(scene, meshes.meshes)
    except SceneError as e:
        raise in_file(SceneError(e.path, e.message), printable(os.fspath(path))) from None
    return meshes


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived: stop as for Ctrl-C (temporary files removed, nothing half-written)."""


class StopEvent(threading.Event):
    """Set by Ctrl-C or SIGTERM; remembers which, so the program ends as that signal asks."""

    signum: int = 0

    def interrupt(self) -> KeyboardInterrupt:
        return Terminated() if self.signum == signal.SIGTERM else KeyboardInterrupt()


@contextlib.contextmanager
def ctrl_c_sets(stop: StopEvent | None = None) -> Iterator[StopEvent]:
    """While rendering, Ctrl-C (or SIGTERM) sets an event that the work polls between bands or
    variants, instead of interrupting numpy, the tracer's threads or the study's workers wherever
    they are. A signal that arrived is raised again as it leaves (``StopEvent.interrupt``)."""
    stop = stop or StopEvent()

    def handler(signum, frame) -> None:
        stop.signum = stop.signum or signum
        stop.set()

    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    previous = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield stop
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
    if stop.is_set():  # after the last band or variant: still nothing is written
        raise stop.interrupt()


def check_utf8(path: str, what: str) -> None:
    """OpenImageIO writes only to paths of UTF-8 characters: a folder or file name holding other bytes
    (they reach Python as lone surrogates) is refused before any rendering."""
    try:
        os.path.abspath(path).encode("utf-8")
    except UnicodeEncodeError:
        raise SceneError(path, f"the {what} path holds bytes that are not UTF-8, which the image library cannot "
                               "write to; allowed a path of UTF-8 characters") from None


def check_output(path: str, what: str) -> None:
    """Before any rendering: the file ``path`` can be written (its folder exists and is writable,
    and it is not a folder, and its path is UTF-8). The message names the user's path."""
    check_utf8(path, what)
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise SceneError(path, f"the {what} folder {folder} does not exist")
    try:
        check_writable(path)
    except OSError as e:
        raise SceneError(path, f"cannot write the {what} here ({e.strerror or e}); allowed a new or "
                               "existing file in a folder you may write to") from None


def check_output_folder(folder: str, what: str) -> None:
    """Before any rendering: files can be written into ``folder`` (or into the folder that will hold it)."""
    check_utf8(folder, what)
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise SceneError(folder, f"{what} must name a folder; this is a file")
    parent = folder if os.path.isdir(folder) else os.path.dirname(os.path.abspath(folder))
    if not os.path.isdir(parent):
        raise SceneError(folder, f"the folder {parent} that would hold {what} does not exist")
    try:
        check_writable(os.path.join(parent, "probe"))
    except OSError as e:
        raise SceneError(folder, f"cannot write {what} here ({e.strerror or e}); allowed a folder you may write "
                                 "to") from None


def add_image_arguments(parser: argparse.ArgumentParser, view: str = display.DEFAULT_VIEW,
                        false_colour: bool = True) -> None:
    """How a command's .png images look: the display options (``add_display_arguments``) and the
    photometric ones (``add_photometric_arguments``)."""
    add_display_arguments(parser, view)
    add_photometric_arguments(parser, false_colour)


def add_display_arguments(parser: argparse.ArgumentParser, view: str = display.DEFAULT_VIEW) -> None:
    """``--view NAME`` and ``--exposure EV|auto``: how a .png shows the linear image (an .exr keeps
    the linear values). The values are checked by ``check_view`` and ``_exposure``. ``view``: the
    default view (AgX, as a new Blender scene, for a render; the lamp view for a sheet)."""
    why = "as in a new Blender scene" if view == display.DEFAULT_VIEW else "the lamp view: red and amber keep their hue"
    parser.add_argument("--view", default=view, metavar="VIEW",
                        help=f"view transform of Blender's colour management for a .png: "
                             f"{', '.join(display.KNOWN_VIEWS)} (default {view}, {why}); Standard is plain sRGB")
    parser.add_argument("--exposure", type=_exposure, default="auto", metavar="EV|auto",
                        help="brighten (+) or darken (-) a .png by this many stops before its view transform; "
                             "auto (the default) puts the lit lens just below the view's shoulder so its cut "
                             "pattern reads")


def view_for(args: argparse.Namespace) -> display.ViewTransform:
    """The view transform ``--view`` names (a ``SceneError`` naming the views there are otherwise);
    where it must fall back to Standard, says why on stderr, once."""
    try:
        view = display.view_transform(args.view)
    except ValueError as e:
        raise SceneError("--view", str(e)) from None
    if view.note:
        print(f"note: {view.note}", file=sys.stderr)
    return view


def _auto_or_number(text: str, lo: float, hi: float, unit: str = "") -> float | str:
    """An argparse type for ``EV|auto`` options: "auto", or a finite number in [lo, hi]."""
    if text.strip().lower() == "auto":
        return "auto"
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number or auto") from None
    if not (math.isfinite(value) and lo <= value <= hi):
        raise argparse.ArgumentTypeError(f"{text} is out of range; allowed auto or [{lo:g}, {hi:g}]{unit}")
    return value


def _exposure(text: str) -> float | str:
    return _auto_or_number(text, -display.MAX_EXPOSURE, display.MAX_EXPOSURE, " stops")


# ---------------------------------------------------------------------------------------------
# The photometric mode's display (docs/photometric.md, "Outputs")


def add_photometric_arguments(parser: argparse.ArgumentParser, false_colour: bool = True) -> None:
    """``--ev100 EV|auto`` (and ``--false-color``, ``--luminance-range LO:HI``): how a photometric
    scene's .png shows its cd/m². The paper mode ignores them."""
    parser.add_argument("--ev100", type=_ev100, metavar="EV|auto",
                        help="photometric scenes: the camera's exposure value at ISO 100 for a .png (default the "
                             "scene's camera.exposure and camera.ev100); one value for every image of a study; "
                             "auto picks one from the lit lens; --exposure adds stops on top")
    if not false_colour:
        return
    parser.add_argument("--false-color", action="store_true",
                        help="photometric scenes: the .png is a false-colour map of the luminance with a legend "
                             "in cd/m2 (log scale, four decades below the image's top unless --luminance-range)")
    parser.add_argument("--luminance-range", type=_luminance_range, metavar="LO:HI",
                        help="the cd/m2 at the two ends of --false-color's scale (e.g. 10:100000), the same for "
                             "images to compare")


def _ev100(text: str) -> float | str:
    ev100 = S.CAMERA.fields["ev100"]  # the range the scene's camera.ev100 accepts
    return _auto_or_number(text, ev100.lo, ev100.hi)


def _luminance_range(text: str) -> tuple[float, float]:
    parts = text.split(":")
    try:
        lo, hi = (float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not LO:HI in cd/m2 (e.g. 10:100000)") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi):
        raise argparse.ArgumentTypeError(f"{text} is out of range; allowed 0 < LO < HI cd/m2")
    return lo, hi


def photometric_stops(args: argparse.Namespace) -> float:
    """The stops a photometric .png adds on top of its EV100: ``--exposure`` when it is a number
    (its "auto" means the camera's own exposure, which the EV100 already is)."""
    return 0.0 if args.exposure == "auto" else float(args.exposure)
