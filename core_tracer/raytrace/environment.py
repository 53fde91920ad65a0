"""The world around the lamp: an equirectangular image looked up as Blender's Environment Texture.

Cycles maps a direction to the image by ``direction_to_equirectangular`` (intern/cycles/kernel/
geom/.. util: range (-2 pi, pi, -pi, pi)): u = -atan2(y, x) / 2 pi + 0.5, v = atan2(z, hypot(x, y))
/ pi + 0.5, v = 1 the zenith, the image's top row; 'Linear' interpolation is bilinear between pixel
centres with the image repeated at its borders. A Mapping node (Point) with Z rotation phi in
front of it looks the image up at R_z(phi) d. The Background node multiplies by its strength. The
tracer's model frame is Blender's world frame (the lamp faces -Y in both), so the same directions
give the same radiance.

The body is lit by the environment as a Lambertian surface: C0 E(n) / pi with E the irradiance
of the environment, from its projection on the first nine spherical harmonics (Ramamoorthi and
Hanrahan 2001: E is a smooth function of n whose three first bands hold all but ~1 % of it),
computed once per image. Occlusion of the environment by the body itself is not modelled.

Blender's own world images (``spec.BUNDLED_WORLDS``) ship with the ``bpy`` module at
``bpy/<version>/datafiles/studiolights/world``; the folder is found from the installed package
without importing it.
"""

from __future__ import annotations

import functools
import importlib.util
import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..scene.reading import SceneError
from ..scene.spec import BUNDLED_WORLDS

SUFFIXES = (".exr", ".hdr")
WORLD_FOLDER = ("datafiles", "studiolights", "world")
# The sun of an image: the pixels at least this fraction of the brightest one (luminance).
SUN_FRACTION = 0.5
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709, Blender's scene-linear primaries


def bundled_folder() -> Path | None:
    """Blender's folder of world images: inside Blender its own, else the installed ``bpy`` module's;
    None where neither is on this machine."""
    running = _running_blender_folder()
    if running is not None:
        return running
    try:
        spec = importlib.util.find_spec("bpy")  # finds the package without importing it
    except (ImportError, ValueError):
        spec = None
    roots = list(spec.submodule_search_locations or []) if spec is not None else []
    for root in roots:
        for version in sorted(Path(root).glob("[0-9]*"), reverse=True):
            folder = version.joinpath(*WORLD_FOLDER)
            if folder.is_dir():
                return folder
    return None


def _running_blender_folder() -> Path | None:
    # Inside Blender bpy is already loaded: ask it for its own data files (never import it here).
    utils = getattr(sys.modules.get("bpy"), "utils", None)
    if utils is None or not hasattr(utils, "system_resource"):
        return None
    try:
        folder = utils.system_resource("DATAFILES", path="/".join(WORLD_FOLDER[1:]))
    except (TypeError, ValueError, AttributeError):
        return None
    return Path(folder) if folder and os.path.isdir(folder) else None


def image_path(env: dict) -> str:
    """The file of a normalised ``environment`` section; a ``SceneError`` naming the field when it
    cannot be read."""
    world = env["world"]
    if world in BUNDLED_WORLDS:
        folder = bundled_folder()
        if folder is None or not (folder / f"{world}.exr").is_file():
            raise SceneError("environment.world", f'"{world}" is one of Blender\'s bundled world images, which are '
                                                  'not on this machine (no bpy module found); allowed "none", or '
                                                  '"file" with an .exr or .hdr image in environment.file')
        return str(folder / f"{world}.exr")
    path = os.path.expanduser(env["file"])
    if not path:
        raise SceneError("environment.file", 'is empty while world is "file"; allowed the path of an .exr or .hdr '
                                             'image')
    if os.path.splitext(path)[1].lower() not in SUFFIXES:
        raise SceneError("environment.file", f"{path!r} is not an environment image; allowed an .exr or .hdr file")
    if not os.path.isfile(path):
        raise SceneError("environment.file", f"{path!r} does not exist; allowed an existing .exr or .hdr file")
    return path


@functools.lru_cache(maxsize=4)
def _read(path: str, mtime_ns: int, size: int) -> np.ndarray:
    """RGB float32 pixels (H, W, 3), top row first (``mtime_ns`` and ``size`` key the cache)."""
    from ..images.imageio import oiio_module  # OpenImageIO only when an environment is used

    oiio = oiio_module()
    buf = oiio.ImageBuf(path)
    pixels = buf.get_pixels(oiio.FLOAT) if not buf.has_error else None
    if pixels is None or buf.has_error or pixels.ndim != 3 or pixels.shape[2] < 1:
        raise SceneError("environment.file", f"{path!r} cannot be read as an image ({buf.geterror() or 'no pixels'}); "
                                             "allowed an .exr or .hdr file")
    if pixels.shape[2] < 3:
        pixels = np.repeat(pixels[..., :1], 3, axis=2)
    pixels = np.ascontiguousarray(pixels[..., :3], dtype=np.float32)
    if not np.isfinite(pixels).all():
        pixels = np.nan_to_num(pixels, nan=0.0, posinf=0.0, neginf=0.0)
    pixels.setflags(write=False)
    return pixels


def _image_key(path: str) -> tuple[str, int, int]:
    st = os.stat(path)
    return path, st.st_mtime_ns, st.st_size


def read_image(path: str) -> np.ndarray:
    return _read(*_image_key(path))


@dataclass(frozen=True)
class Environment:
    pixels: np.ndarray  # (H, W, 3) float32, top row first
    strength: float
    rotation: float  # radians about +z, the Mapping node's
    key: tuple = ()  # the image file's (path, mtime, size): what it holds is computed once per image and turn

    # -- looking up radiance ------------------------------------------------------------------

    def texture_coordinates(self, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """u, v of unit directions ``d`` (N, 3) in the image, as Cycles (module docstring)."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        x = c * d[:, 0] - s * d[:, 1]
        y = s * d[:, 0] + c * d[:, 1]
        u = -np.arctan2(y, x) / (2.0 * math.pi) + 0.5
        v = np.arctan2(d[:, 2], np.hypot(x, y)) / math.pi + 0.5
        return u, v

    def radiance(self, d: np.ndarray) -> np.ndarray:
        """Radiance (N, 3) arriving from unit directions ``d`` (N, 3): bilinear, repeated borders."""
        u, v = self.texture_coordinates(d)
        h, w = self.pixels.shape[:2]
        # Cycles' bilinear lookup: pixel i covers [i, i + 1) of u W; rows count from the bottom.
        x = u * w - 0.5
        y = (1.0 - v) * h - 0.5
        x0 = np.floor(x)
        y0 = np.floor(y)
        tx = (x - x0)[:, None]
        ty = (y - y0)[:, None]
        x0 = x0.astype(np.int64) % w
        y0 = y0.astype(np.int64) % h
        x1 = (x0 + 1) % w
        y1 = (y0 + 1) % h
        p = self.pixels
        top = p[y0, x0] * (1.0 - tx) + p[y0, x1] * tx
        bottom = p[y1, x0] * (1.0 - tx) + p[y1, x1] * tx
        return self.strength * (top * (1.0 - ty) + bottom * ty)

    # -- what the image holds ------------------------------------------------------------------

    def _pixel_directions(self) -> tuple[np.ndarray, np.ndarray]:
        """World directions of the pixel centres (H*W, 3) and their solid angles (H*W,)."""
        h, w = self.pixels.shape[:2]
        u = (np.arange(w) + 0.5) / w
        v = 1.0 - (np.arange(h) + 0.5) / h
        phi = (0.5 - u) * 2.0 * math.pi  # texture azimuth: atan2(y, x) in the texture's frame
        lat = (v - 0.5) * math.pi
        lat, phi = np.meshgrid(lat, phi, indexing="ij")
        t = np.stack([np.cos(lat) * np.cos(phi), np.cos(lat) * np.sin(phi), np.sin(lat)], axis=-1).reshape(-1, 3)
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        world = np.stack([c * t[:, 0] + s * t[:, 1], -s * t[:, 0] + c * t[:, 1], t[:, 2]], axis=1)  # R_z(-phi) t
        solid = (np.cos(lat) * (2.0 * math.pi / w) * (math.pi / h)).reshape(-1)
        return world, solid

    @functools.cached_property
    def _irradiance_sh(self) -> np.ndarray:
        """The environment's radiance on the first nine spherical harmonics, (9, 3)."""
        if self.key:
            return self.strength * _cached_sh(self.key, self.rotation)
        return self.strength * _radiance_sh(self.pixels, self.rotation)

    def irradiance(self, normal: np.ndarray) -> np.ndarray:
        """Irradiance (N, 3) on surfaces of unit ``normal`` (N, 3) from the whole environment."""
        # Convolution with the clamped cosine: A_l = pi, 2 pi / 3, pi / 4 (Ramamoorthi & Hanrahan).
        band = np.array([math.pi] + [2.0 * math.pi / 3.0] * 3 + [math.pi / 4.0] * 5)
        return np.maximum(0.0, _sh9(normal) @ (band[:, None] * self._irradiance_sh))

    def sun_direction(self) -> np.ndarray:
        """Unit direction toward the image's sun: the solid-angle weighted centroid of its pixels of at
        least ``SUN_FRACTION`` of the brightest luminance."""
        if self.key:
            return _cached_sun(self.key, self.rotation).copy()
        return _sun_direction(self.pixels, self.rotation)


def _pixel_directions(pixels: np.ndarray, rotation: float) -> tuple[np.ndarray, np.ndarray]:
    return Environment(pixels, 1.0, rotation)._pixel_directions()


def _radiance_sh(pixels: np.ndarray, rotation: float) -> np.ndarray:
    d, solid = _pixel_directions(pixels, rotation)
    return _sh9(d).T @ (pixels.reshape(-1, 3).astype(np.float64) * solid[:, None])


def _sun_direction(pixels: np.ndarray, rotation: float) -> np.ndarray:
    d, solid = _pixel_directions(pixels, rotation)
    lum = pixels.reshape(-1, 3).astype(np.float64) @ LUMINANCE
    sun = lum >= SUN_FRACTION * lum.max()
    centre = ((lum * solid)[sun, None] * d[sun]).sum(axis=0)
    norm = float(np.linalg.norm(centre))
    return centre / norm if norm > 0 else np.array([0.0, 0.0, 1.0])


@functools.lru_cache(maxsize=8)
def _cached_sh(key: tuple, rotation: float) -> np.ndarray:
    return _radiance_sh(_read(*key), rotation)


@functools.lru_cache(maxsize=8)
def _cached_sun(key: tuple, rotation: float) -> np.ndarray:
    return _sun_direction(_read(*key), rotation)


def _sh9(d: np.ndarray) -> np.ndarray:
    """The nine real spherical harmonics up to l = 2 at unit directions ``d`` (N, 3): (N, 9)."""
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    return np.stack([
        np.full(len(d), 0.282095),
        0.488603 * y, 0.488603 * z, 0.488603 * x,
        1.092548 * x * y, 1.092548 * y * z, 0.315392 * (3.0 * z * z - 1.0), 1.092548 * x * z,
        0.546274 * (x * x - y * y)], axis=1)


def from_scene(scene: dict) -> Environment | None:
    """The environment of a normalised scene, or None for the paper's plain background."""
    env = scene.get("environment")  # a scene an earlier version built in code has none
    if env is None or env["world"] == "none":
        return None
    key = _image_key(image_path(env))
    return Environment(_read(*key), float(env["strength"]), math.radians(env["rotation_deg"]), key)
