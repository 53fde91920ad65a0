"""Image files through OpenImageIO: linear float EXR with the scene in the header, 8-bit display PNG.

An EXR keeps the tracer's linear RGB exactly (32-bit float) and carries the normalised scene
JSON in the header attribute ``lamp:scene``, so an image can always be traced back to its
design. A PNG is display-referred: exposure and a view transform of Blender's colour management
(``display``), 8 bits, with the scene JSON as a text chunk of the same name and the view and
exposure as ``lamp:view`` and ``lamp:exposure``. Every write goes through ``fileio.atomic_path``:
a failure never leaves a partial file.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator, Mapping, Sequence

import numpy as np

from .. import fileio
from ..scene.reading import SceneError, parse_json_text, scene_to_json
from ..scene.safe_text import printable
from ..scene.validate import normalize, parse_scene
from . import display

SCENE_ATTRIBUTE = "lamp:scene"
VIEW_ATTRIBUTE = "lamp:view"  # the view transform of a PNG; read_image undoes it
EXPOSURE_ATTRIBUTE = "lamp:exposure"  # stops applied to a PNG before its view; read_image undoes them
SUFFIXES = (".exr", ".png")
RGB = ("R", "G", "B")

# CIE XYZ in an EXR that other tools read as XYZ (issue 31 item 3). OpenEXR's ``chromaticities``
# give the CIE xy of the file's three primaries and its white; ``whiteLuminance`` the luminance in
# cd/m² of the value (1, 1, 1) (openexr.com, "Standard Optional Attributes"). With the X, Y and Z
# axes as primaries, (1, 0), (0, 1) and (0, 0), the value (1, 1, 1) is XYZ (1, 1, 1): white
# (1/3, 1/3), illuminant E, and luminance Y = 1 cd/m² when Y is in cd/m². Blender then reads the
# file as "Linear CIE-XYZ E" by itself, whatever the channels are named (checked with bpy 5.0.1);
# without them every reader takes the values for Rec.709 R, G, B.
XYZ_CHROMATICITIES = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0 / 3.0, 1.0 / 3.0)
XYZ_WHITE_LUMINANCE = 1.0  # cd/m² of X = Y = Z = 1, with Y in cd/m²


def _oiio():
    # Imported on use: core_tracer renders without OpenImageIO; only files need it.
    try:
        import OpenImageIO
    except ImportError as e:
        # pybind11 turns a Ctrl-C or SIGTERM that lands during the module's initialisation into
        # "ImportError: initialization failed": it is the interrupt, not a broken installation.
        if isinstance(e.__cause__, KeyboardInterrupt):
            raise e.__cause__ from None
        raise
    return OpenImageIO


oiio_module = _oiio  # for the modules that compose images with it


def load_writer() -> None:
    """Import OpenImageIO now, before long work: an interrupt that lands while it is half imported
    ends the program cleanly here, rather than breaking a later import of it (pybind11 refuses to
    register its types twice)."""
    _oiio()



def image_format(path: str | os.PathLike) -> str:
    """``"exr"`` or ``"png"`` from the file name; a ``SceneError`` naming the path otherwise."""
    name = os.fspath(path)
    suffix = os.path.splitext(name)[1].lower()
    if suffix not in SUFFIXES:
        allowed = ", ".join(SUFFIXES)
        raise SceneError(name, f"{suffix or 'no suffix'} is not an image format this writes; allowed {allowed}")
    return suffix[1:]


def _check_image(image: np.ndarray, what: str) -> np.ndarray:
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"{what}: expected an array of shape (height, width, 3), got {a.shape}")
    return _finite(a.astype(np.float32, copy=False), what)


def _finite(a: np.ndarray, what: str) -> np.ndarray:
    """The writers' last guard (issue 33): no NaN or inf reaches a file, whatever command made the image."""
    if not np.isfinite(a).all():
        raise SceneError(what, "holds values that are not finite numbers (NaN or inf); allowed finite images only "
                               "(nothing was written)")
    return a


def write_image(
    path: str | os.PathLike,
    image: np.ndarray,
    scene: dict | None = None,
    *,
    attributes: Mapping[str, str] | None = None,
    view: display.ViewTransform | None = None,
    exposure: float | str | None = "auto",
    xyz: bool = False,
) -> float:
    """Write ``image`` (H, W, 3 linear RGB, top row first) as EXR or PNG, chosen by the suffix.

    ``scene`` is normalised and stored as JSON in the ``lamp:scene`` attribute; ``attributes``
    are further string attributes of the header. An EXR keeps the linear values. A PNG shows the
    image through ``view`` (default: ``display.view_transform()``, Blender's AgX) at ``exposure``
    stops (a number, or "auto"/None for ``display.auto_exposure``). Returns the exposure applied
    (0 for an EXR). ``xyz``: an EXR whose three channels hold CIE XYZ (Y in cd/m²) and say so
    (``XYZ_CHROMATICITIES``). Raises ``SceneError`` for an unsupported suffix, ``OSError`` when the
    file cannot be written.
    """
    name = os.fspath(path)
    fmt = image_format(name)
    rgb = _check_image(image, "image")
    if fmt == "exr":
        _write(name, rgb, scene, attributes, xyz=xyz)
        return 0.0
    if xyz:
        raise ValueError("a .png shows XYZ through display.shown first; xyz is for an .exr")
    view = view or display.view_transform()
    ev = display.resolve_exposure(exposure, rgb)
    extra = {VIEW_ATTRIBUTE: view.view, EXPOSURE_ATTRIBUTE: f"{ev:g}", **(attributes or {})}
    _write(name, view.to_display8(rgb, ev), scene, extra)
    return ev


def write_display(path: str | os.PathLike, shown: np.ndarray, scene: dict | None = None, *,
                  attributes: Mapping[str, str] | None = None, view: str = display.STANDARD,
                  exposure: float = 0.0) -> None:
    """Write display values ``shown`` (H, W, 3 in [0, 1], top row first) as an 8-bit PNG, for images
    composed on the display side (labels on a sheet); ``view`` and ``exposure`` say how the
    pictures in it were made, for ``read_image`` to undo."""
    name = os.fspath(path)
    if image_format(name) != "png":
        raise SceneError(name, "display values are written as .png; an .exr holds linear values")
    codes = np.rint(np.clip(_check_image(shown, "image"), 0.0, 1.0) * 255.0).astype(np.uint8)
    extra = {VIEW_ATTRIBUTE: view, EXPOSURE_ATTRIBUTE: f"{exposure:g}", **(attributes or {})}
    _write(name, codes, scene, extra)


def write_channels(path: str | os.PathLike, pixels: np.ndarray, channel_names: Sequence[str], *,
                   scene: dict | None = None, attributes: Mapping[str, str] | None = None,
                   xyz: bool = False) -> None:
    """Write float ``pixels`` (H, W, C, top row first) as an EXR whose channels are named
    ``channel_names``, with the scene and string ``attributes`` in its header; atomically, as every image.
    ``xyz``: the first three channels are CIE XYZ with Y in cd/m² (``XYZ_CHROMATICITIES``)."""
    _write(os.fspath(path), _finite(np.asarray(pixels, dtype=np.float32), "image"), scene, attributes,
           tuple(channel_names), xyz=xyz)


def _write(name: str, pixels: np.ndarray, scene: dict | None, attributes: Mapping[str, str] | None,
           channel_names: tuple[str, ...] = RGB, *, xyz: bool = False) -> None:
    scene_text = scene_to_json(normalize(scene)) if scene is not None else None
    oiio = _oiio()
    height, width = pixels.shape[:2]
    if pixels.dtype == np.uint8:
        spec = oiio.ImageSpec(width, height, len(channel_names), oiio.UINT8)
        spec.attribute("oiio:ColorSpace", "sRGB")
    else:
        spec = oiio.ImageSpec(width, height, len(channel_names), oiio.FLOAT)
        spec.attribute("compression", "zip")
    spec.channelnames = channel_names
    if xyz:
        spec.attribute("chromaticities", oiio.TypeDesc("float[8]"), XYZ_CHROMATICITIES)
        spec.attribute("whiteLuminance", XYZ_WHITE_LUMINANCE)
    if scene_text is not None:
        spec.attribute(SCENE_ATTRIBUTE, scene_text)
    for key, value in (attributes or {}).items():
        spec.attribute(key, value)
    pixels = np.ascontiguousarray(pixels)

    # Ctrl-C or SIGTERM waits for the write (milliseconds): a file closed between open and
    # write_image makes libpng print its own error ("No IDATs written") beside our one line.
    try:
        os.path.abspath(name).encode("utf-8")
    except UnicodeEncodeError:  # it reaches Python as lone surrogates; OpenImageIO takes only UTF-8 names
        raise OSError(f"{printable(name)}: cannot write the image (its folder or name holds bytes that are not "
                      "UTF-8, which OpenImageIO cannot write to)") from None
    with fileio.atomic_path(name) as tmp, fileio.signals_deferred():
        out = oiio.ImageOutput.create(tmp)
        if out is None:
            raise OSError(f"{name}: OpenImageIO cannot write this format ({oiio.geterror()})")
        try:
            if not out.open(tmp, spec):
                raise OSError(f"{name}: cannot write the image ({out.geterror()})")
            if not out.write_image(pixels):
                raise OSError(f"{name}: cannot write the image ({out.geterror()})")
        finally:
            closed = out.close()
        if not closed:
            raise OSError(f"{name}: cannot finish the image ({out.geterror()})")


@contextlib.contextmanager
def _opened(path: str | os.PathLike) -> Iterator[tuple[str, object, object]]:
    """The one way images are opened for reading: (name, OpenImageIO module, ImageInput), closed after."""
    name = os.fspath(path)
    if not os.path.isfile(name):
        raise SceneError(name, "cannot read the image (no such file)")
    try:
        name.encode("utf-8")
    except UnicodeEncodeError:
        raise SceneError(name, "cannot read the image (its folder or name holds bytes that are not UTF-8, which "
                               "OpenImageIO cannot open)") from None
    oiio = _oiio()
    inp = oiio.ImageInput.open(name)
    if inp is None:
        raise SceneError(name, f"cannot read the image ({oiio.geterror()})")
    try:
        yield name, oiio, inp
    finally:
        inp.close()


def read_attribute(path: str | os.PathLike, attribute: str) -> object:
    """One header attribute of an image file (None when it has none), without reading the pixels."""
    with _opened(path) as (_name, _oiio_module, inp):
        return inp.spec().getattribute(attribute)


def _read(path: str | os.PathLike):
    with _opened(path) as (name, oiio, inp):
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None:
            raise SceneError(name, f"cannot read the image ({inp.geterror()})")
    pixels = np.asarray(pixels, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    return name, spec, pixels


def _channels(name: str, spec, pixels: np.ndarray, wanted: tuple[str, ...]) -> np.ndarray:
    index = {c: i for i, c in enumerate(spec.channelnames)}
    missing = [c for c in wanted if c not in index]
    if missing:
        raise SceneError(name, f"the image has no channel {missing[0]}; it has {', '.join(spec.channelnames)}")
    return np.ascontiguousarray(pixels[:, :, [index[c] for c in wanted]], dtype=np.float32)


def read_image(path: str | os.PathLike) -> tuple[np.ndarray, dict | None]:
    """Read an image written by ``write_image``: (linear float32 H, W, 3 top row first, scene or None).

    A PNG's 8-bit codes are taken back to linear through the inverse of its view and exposure (a
    PNG without ``lamp:view`` is plain sRGB); where a view clipped, so does the result. The scene is
    parsed and validated with ``parse_scene``; a header that does not hold a valid scene raises ``SceneError``.
    """
    fmt = image_format(path)
    name, spec, pixels = _read(path)
    if spec.nchannels == 1:  # a grey image from elsewhere
        rgb = np.repeat(pixels, 3, axis=2)
    else:
        rgb = _channels(name, spec, pixels, RGB)
    if fmt == "png":
        rgb = _undo_display(name, spec, rgb)
    text = spec.getattribute(SCENE_ATTRIBUTE)
    if text is None:
        return rgb, None
    if not isinstance(text, str):
        raise SceneError(name, f"the {SCENE_ATTRIBUTE} attribute is not text")
    try:
        scene = parse_scene(parse_json_text(text, SCENE_ATTRIBUTE))
    except SceneError as e:
        raise SceneError(name, f"{SCENE_ATTRIBUTE} holds no valid scene ({e})") from None
    return rgb, scene


def _undo_display(name: str, spec, shown: np.ndarray) -> np.ndarray:
    view_name = spec.getattribute(VIEW_ATTRIBUTE)
    exposure = spec.getattribute(EXPOSURE_ATTRIBUTE)
    try:
        ev = float(exposure) if isinstance(exposure, str) else 0.0
    except ValueError:
        raise SceneError(name, f"{EXPOSURE_ATTRIBUTE} {exposure[:40]!r} is not a number") from None
    try:
        view = display.view_transform(view_name if isinstance(view_name, str) else display.STANDARD)
    except ValueError as e:
        raise SceneError(name, f"{VIEW_ATTRIBUTE}: {e}") from None
    return view.to_linear(shown, ev)
