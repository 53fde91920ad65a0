"""Image files through OpenImageIO: linear float EXR with the scene in the header, sRGB 8-bit PNG.

An EXR keeps the tracer's linear RGB exactly (32-bit float) and carries the normalised scene
JSON in the header attribute ``lamp:scene``, so an image can always be traced back to its
design; contribution passes may ride along as extra channels (``bulb.R``, ``bulb.G``, ...).
A PNG is display-referred: the exact sRGB transfer function, 8 bits, with the scene JSON as a
text chunk of the same name. Every write goes through ``fileio.atomic_path``: a failure never
leaves a partial file.
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np

from . import fileio
from .scene import SceneError, normalize, parse_json_text, parse_scene, scene_to_json

SCENE_ATTRIBUTE = "lamp:scene"
SUFFIXES = (".exr", ".png")
RGB = ("R", "G", "B")


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


EXPOSURE_ATTRIBUTE = "lamp:exposure"  # stops applied to a PNG before encoding; read_image undoes it


def image_format(path: str | os.PathLike) -> str:
    """``"exr"`` or ``"png"`` from the file name; a ``SceneError`` naming the path otherwise."""
    name = os.fspath(path)
    suffix = os.path.splitext(name)[1].lower()
    if suffix not in SUFFIXES:
        allowed = ", ".join(SUFFIXES)
        raise SceneError(name, f"{suffix or 'no suffix'} is not an image format this writes; allowed {allowed}")
    return suffix[1:]


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """The sRGB transfer function (IEC 61966-2-1) of linear values, clipped to [0, 1]."""
    x = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)


def srgb_decode(encoded: np.ndarray) -> np.ndarray:
    """The inverse of ``srgb_encode``: display values in [0, 1] back to linear."""
    v = np.asarray(encoded, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, np.power((v + 0.055) / 1.055, 2.4))


SRGB_CHUNK = 1 << 20  # values encoded at a time: the float64 temporaries stay a few MB at any size


def to_srgb8(linear: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """Linear RGB (times ``scale``, in float32 as the image) to 8-bit sRGB codes, rounded to nearest.

    Encoded in chunks: whole-image float64 temporaries of an 8192 x 8192 image would need about
    8 GB; the codes are the same either way."""
    a = np.asarray(linear)
    flat = a.reshape(-1)
    out = np.empty(flat.shape, dtype=np.uint8)
    for start in range(0, flat.size, SRGB_CHUNK):
        part = flat[start:start + SRGB_CHUNK]
        if scale != 1.0:
            part = part * np.float32(scale)
        out[start:start + SRGB_CHUNK] = np.rint(srgb_encode(part) * 255.0)
    return out.reshape(a.shape)


def _check_image(image: np.ndarray, what: str) -> np.ndarray:
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 3 or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"{what}: expected an array of shape (height, width, 3), got {a.shape}")
    return a.astype(np.float32, copy=False)


def write_image(
    path: str | os.PathLike,
    image: np.ndarray,
    scene: dict | None = None,
    *,
    passes: Mapping[str, np.ndarray] | None = None,
    attributes: Mapping[str, str] | None = None,
    exposure: float = 0.0,
) -> None:
    """Write ``image`` (H, W, 3 linear RGB, top row first) as EXR or PNG, chosen by the suffix.

    ``scene`` is normalised and stored as JSON in the ``lamp:scene`` attribute; ``attributes``
    are further string attributes of the header. ``passes`` (name -> H, W, 3) become extra
    channels ``name.R/G/B`` of an EXR; a PNG cannot hold them. ``exposure`` (stops) scales a PNG
    before its sRGB encoding, so bright lamps need not clip; an EXR always keeps the linear values.
    Raises ``SceneError`` for an unsupported suffix, ``OSError`` when the file cannot be written.
    """
    name = os.fspath(path)
    fmt = image_format(name)
    rgb = _check_image(image, "image")
    channels = [rgb]
    names = list(RGB)
    for pass_name, data in (passes or {}).items():
        if fmt != "exr":
            raise SceneError(name, "passes can only be stored in an .exr file")
        if not pass_name or "." in pass_name or pass_name in RGB:
            raise ValueError(f"pass name {pass_name!r} cannot name an EXR channel layer")
        p = _check_image(data, f"pass {pass_name}")
        if p.shape != rgb.shape:
            raise ValueError(f"pass {pass_name}: shape {p.shape} differs from the image {rgb.shape}")
        channels.append(p)
        names += [f"{pass_name}.{c}" for c in RGB]
    scene_text = scene_to_json(normalize(scene)) if scene is not None else None

    oiio = _oiio()
    height, width = rgb.shape[:2]
    if fmt == "exr":
        pixels = np.ascontiguousarray(np.concatenate(channels, axis=2), dtype=np.float32)
        spec = oiio.ImageSpec(width, height, len(names), oiio.FLOAT)
        spec.channelnames = tuple(names)
        spec.attribute("compression", "zip")
    else:
        pixels = to_srgb8(rgb, 2.0**exposure if exposure else 1.0)
        spec = oiio.ImageSpec(width, height, 3, oiio.UINT8)
        spec.attribute("oiio:ColorSpace", "sRGB")
        if exposure:
            spec.attribute(EXPOSURE_ATTRIBUTE, f"{exposure:g}")
    if scene_text is not None:
        spec.attribute(SCENE_ATTRIBUTE, scene_text)
    for key, value in (attributes or {}).items():
        spec.attribute(key, value)

    with fileio.atomic_path(name) as tmp:
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


def _read(path: str | os.PathLike):
    name = os.fspath(path)
    if not os.path.isfile(name):
        raise SceneError(name, "cannot read the image (no such file)")
    oiio = _oiio()
    inp = oiio.ImageInput.open(name)
    if inp is None:
        raise SceneError(name, f"cannot read the image ({oiio.geterror()})")
    try:
        spec = inp.spec()
        pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
        if pixels is None:
            raise SceneError(name, f"cannot read the image ({inp.geterror()})")
    finally:
        inp.close()
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

    A PNG's 8-bit sRGB codes are decoded back to linear (and its exposure undone). The scene is
    parsed and validated with ``parse_scene``; a header that does not hold a valid scene raises ``SceneError``.
    """
    fmt = image_format(path)
    name, spec, pixels = _read(path)
    if spec.nchannels == 1:  # a grey image from elsewhere
        rgb = np.repeat(pixels, 3, axis=2)
    else:
        rgb = _channels(name, spec, pixels, RGB)
    if fmt == "png":
        rgb = srgb_decode(rgb)
        exposure = spec.getattribute(EXPOSURE_ATTRIBUTE)
        if isinstance(exposure, str):
            try:
                rgb = rgb / 2.0 ** float(exposure)
            except ValueError:
                raise SceneError(name, f"{EXPOSURE_ATTRIBUTE} {exposure[:40]!r} is not a number") from None
        rgb = rgb.astype(np.float32)
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


def read_passes(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The extra ``name.R/G/B`` channel layers of an EXR, as name -> (H, W, 3) float32."""
    name, spec, pixels = _read(path)
    layers: list[str] = []
    for channel in spec.channelnames:
        layer, _, c = channel.rpartition(".")
        if layer and c == "R" and layer not in layers:
            layers.append(layer)
    return {layer: _channels(name, spec, pixels, tuple(f"{layer}.{c}" for c in RGB)) for layer in layers}
