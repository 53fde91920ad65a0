"""The world around the lamp: an equirectangular image looked up as Blender's Environment Texture.

Cycles maps a direction to the image by ``direction_to_equirectangular`` (intern/cycles/kernel/
geom/.. util: range (-2 pi, pi, -pi, pi)): u = -atan2(y, x) / 2 pi + 0.5, v = atan2(z, hypot(x, y))
/ pi + 0.5, v = 1 the zenith, the image's top row; 'Linear' interpolation is bilinear between pixel
centres with the image repeated at its borders. A Mapping node (Point) with Z rotation phi in
front of it looks the image up at R_z(phi) d. The Background node multiplies by its strength. The
tracer's model frame is Blender's world frame (the lamp faces -Y in both), so the same directions
give the same radiance.

The body is lit by the environment as a Lambertian surface: C0 E(n) / pi with E the irradiance
of the environment, the cosine-weighted integral of its radiance over the hemisphere about n. E is
a smooth function of n, so it is computed once per image and turn on a grid of normals (nodes every
360/64 degrees of longitude and 180/32 of latitude, the six axis directions among them; the image
area-averaged to at most 128 x 64 for the integral) and interpolated bilinearly between the nodes.
Occlusion of the environment by the body itself is not modelled.

The image is read by ``world_image`` (its header checked before any pixel, its values finite and
bounded, down-sampled past a size) and what the lookups need of it, the padded pixels, the
irradiance map and the sun, is made once per image and turn and shared between processes through
a mapped cache file (``world_cache``).

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
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..scene.reading import SceneError
from ..scene.spec import BUNDLED_WORLDS
from . import world_cache, world_image

SUFFIXES = (".exr", ".hdr")
WORLD_FOLDER = ("datafiles", "studiolights", "world")
# The irradiance map: nodes every 2 pi / IRRADIANCE_LON in longitude, pi / IRRADIANCE_LAT in latitude.
IRRADIANCE_LON, IRRADIANCE_LAT = 64, 32
IRRADIANCE_SOURCE = (128, 64)  # the image is area-averaged to at most this for the integral
# The sun of an image: the pixels at least this fraction of the brightest one (luminance).
SUN_FRACTION = 0.5
# The sun taken out of the image where an explicit sun stands for it (``sunless``): the pixels within
# SUN_REACH_DEG of its direction, at least SUN_EDGE of the brightest luminance and SUN_OVER_SKY times
# the sky's around it.
SUN_EDGE = 0.01
SUN_OVER_SKY = 4.0
SUN_REACH_DEG = 5.0
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709, Blender's scene-linear primaries


def bundled_folder() -> Path | None:
    """Blender's folder of world images: inside Blender its own, else the installed ``bpy`` module's;
    None where neither is on this machine."""
    running = _running_blender_folder() or _beside_blenders_python()
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


def _beside_blenders_python() -> Path | None:
    """A worker Blender starts runs <version>/python/bin/python3.x without bpy: worlds in <version>/datafiles."""
    parents = Path(sys.executable).absolute().parents if sys.executable else ()
    folder = parents[2].joinpath(*WORLD_FOLDER) if len(parents) > 2 else None
    return folder if folder is not None and folder.is_dir() else None


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


def read_image(path: str) -> np.ndarray:
    """RGB float32 pixels (H, W, 3) of the image at ``path``, top row first, read as the tracer reads
    them (``world_image``: checked by its header, finite, down-sampled where too large)."""
    world = world_cache.world(path, 0.0, LAYOUT, _make_world)
    pixels = np.ascontiguousarray(world.pixels)
    pixels.setflags(write=False)
    return pixels


@dataclass(frozen=True)
class Environment:
    pixels: np.ndarray  # (H, W, 3) float32, top row first
    strength: float
    rotation: float  # radians about +z, the Mapping node's
    world: world_cache.World | None = None  # what the image holds, made once per image and turn (from_scene)

    # -- looking up radiance ------------------------------------------------------------------

    def texture_coordinates(self, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """u, v of unit directions ``d`` (N, 3) in the image, as Cycles (module docstring)."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        # x = c d0 - s d1, y = s d0 + c d1, u = -atan2(y, x) / 2 pi + 0.5, v = atan2(d2, hypot(x, y)) / pi
        # + 0.5: the same operations on the same arrays, the arithmetic in place.
        x = c * d[:, 0]
        term = s * d[:, 1]
        x -= term
        y = s * d[:, 0]
        np.multiply(c, d[:, 1], out=term)
        y += term
        u = np.arctan2(y, x)
        np.negative(u, out=u)
        u /= 2.0 * math.pi
        u += 0.5
        v = np.arctan2(d[:, 2], np.hypot(x, y))
        v /= math.pi
        v += 0.5
        return u, v

    def radiance(self, d: np.ndarray) -> np.ndarray:
        """Radiance (N, 3) arriving from unit directions ``d`` (N, 3): bilinear, repeated borders."""
        u, v = self.texture_coordinates(d)
        h, w = self.pixels.shape[:2]
        # Cycles' bilinear lookup: pixel i covers [i, i + 1) of u W; v counts rows from the bottom.
        x = u  # x = u w - 0.5, y = (1 - v) h - 0.5, tx = x - floor(x), ty = y - floor(y), in place
        x *= w
        x -= 0.5
        y = np.subtract(1.0, v, out=v)
        y *= h
        y -= 0.5
        x0 = np.floor(x)
        y0 = np.floor(y)
        tx = np.subtract(x, x0, out=x)
        ty = np.subtract(y, y0, out=y)
        # x0 lies in [-1, w - 1], y0 in [-1, h - 1] (u, v in [0, 1]): the padded image (``_padded``) holds
        # the repeated border, so the corners need no modulo (the same values as p[y % h, x % w]).
        corner = y0.astype(np.int64)
        corner += 1
        corner *= w + 3
        column = x0.astype(np.int64)
        column += 1
        corner += column
        below = corner + (w + 3)
        # The four corners' pixels, their channels side by side (one row of the padded image each).
        padded = self._padded
        top_left = padded.take(corner, axis=0, mode="clip")
        corner += 1
        top_right = padded.take(corner, axis=0, mode="clip")
        bottom_left = padded.take(below, axis=0, mode="clip")
        below += 1
        bottom_right = padded.take(below, axis=0, mode="clip")
        sx = 1.0 - tx
        sy = 1.0 - ty
        # The same products and sums, in the same order, as top * (1 - ty) + bottom * ty of the rows
        # (float32 pixels times float64 weights: float64 products, as before padding), a channel at a
        # time: numpy broadcasts (N, 1) weights over rows of 3 slowly.
        out = np.empty((len(d), 3))
        for channel in range(3):
            top = _bilinear(top_left[:, channel], top_right[:, channel], bottom_left[:, channel],
                            bottom_right[:, channel], sx, tx, sy, ty)
            np.multiply(top, self.strength, out=out[:, channel])
        return out

    @functools.cached_property
    def _padded(self) -> np.ndarray:
        """The image's pixels padded to (H + 3) x (W + 3), flattened to ((H + 3) * (W + 3), 4): row
        (j + 1) (W + 3) + i + 1 holds pixel (j % h, i % w) for j in [-1, h + 1], i in [-1, w + 1] (the
        repeated border), its three channels and a 0 (rows of 16 bytes, which ``take`` copies fastest).
        Made once per image (``world_cache``)."""
        return self.world.padded if self.world is not None else _pad(self.pixels)

    # -- what the image holds ------------------------------------------------------------------

    def _pixel_directions(self) -> tuple[np.ndarray, np.ndarray]:
        """World directions of the pixel centres (H*W, 3) and their solid angles (H*W,)."""
        h, w = self.pixels.shape[:2]
        return _pixel_directions(h, w, self.rotation)

    @functools.cached_property
    def _irradiance_map(self) -> np.ndarray:
        """Irradiance at the grid's nodes, (IRRADIANCE_LAT + 1, IRRADIANCE_LON, 3)."""
        unit = self.world.irradiance if self.world is not None else _irradiance(self.pixels, self.rotation)
        return self.strength * unit

    def irradiance(self, normal: np.ndarray) -> np.ndarray:
        """Irradiance (N, 3) on surfaces of unit ``normal`` (N, 3) from the whole environment."""
        # x = (atan2(n1, n0) + pi) / 2 pi LON, y = (asin(n2) + pi / 2) / pi LAT, in place
        x = np.arctan2(normal[:, 1], normal[:, 0])
        x += math.pi
        x /= 2.0 * math.pi
        x *= IRRADIANCE_LON
        y = np.arcsin(np.clip(normal[:, 2], -1.0, 1.0))
        y += 0.5 * math.pi
        y /= math.pi
        y *= IRRADIANCE_LAT
        i0 = np.floor(x)
        j0 = np.minimum(np.floor(y), IRRADIANCE_LAT - 1)
        tx = np.subtract(x, i0, out=x)
        ty = np.subtract(y, j0, out=y)
        i0 = i0.astype(np.int64) % IRRADIANCE_LON
        i1 = (i0 + 1) % IRRADIANCE_LON
        # The nodes (j0, i0), (j0, i1), (j0 + 1, i0), (j0 + 1, i1) as rows of the flattened map.
        row = j0.astype(np.int64)
        row *= IRRADIANCE_LON
        top_left, top_right = row + i0, row + i1
        row += IRRADIANCE_LON
        bottom_left, bottom_right = row + i0, row + i1
        sx = 1.0 - tx
        sy = 1.0 - ty
        # (m00 (1 - tx) + m01 tx) (1 - ty) + (m10 (1 - tx) + m11 tx) ty, a channel at a time:
        # numpy broadcasts (N, 1) weights over rows of 3 slowly.
        out = np.empty((len(normal), 3))
        for channel, plane in enumerate(self._irradiance_planes):
            out[:, channel] = _bilinear(plane.take(top_left), plane.take(top_right), plane.take(bottom_left),
                                        plane.take(bottom_right), sx, tx, sy, ty)
        return out

    @functools.cached_property
    def _irradiance_planes(self) -> np.ndarray:
        """The irradiance map, one flat plane per channel (3, (IRRADIANCE_LAT + 1) * IRRADIANCE_LON)."""
        return np.ascontiguousarray(self._irradiance_map.reshape(-1, 3).T)

    def sun_direction(self) -> np.ndarray:
        """Unit direction toward the image's sun: the solid-angle weighted centroid of its pixels of at
        least ``SUN_FRACTION`` of the brightest luminance."""
        if self.world is not None:
            return np.array(self.world.sun_direction)
        return _sun_direction(self.pixels, self.rotation)

    def sun_color(self) -> np.ndarray:
        """The colour of the image's sun (the pixels ``sun_direction`` takes) at luminance 1, whatever
        the strength and the turn (``sunlight.followed_color``)."""
        if self.world is not None:
            return np.array(self.world.sun_color)
        return _sun_color(self.pixels)


def _bilinear(top_left: np.ndarray, top_right: np.ndarray, bottom_left: np.ndarray, bottom_right: np.ndarray,
              sx: np.ndarray, tx: np.ndarray, sy: np.ndarray, ty: np.ndarray) -> np.ndarray:
    """One channel of a bilinear lookup, (top_left sx + top_right tx) sy + (bottom_left sx +
    bottom_right tx) ty, in that order (sx = 1 - tx, sy = 1 - ty)."""
    top = top_left * sx
    top += top_right * tx
    bottom = bottom_left * sx
    bottom += bottom_right * tx
    top *= sy
    bottom *= ty
    top += bottom
    return top


def _pad(pixels: np.ndarray) -> np.ndarray:
    """``Environment._padded`` of ``pixels``."""
    h, w = pixels.shape[:2]
    rows = np.arange(-1, h + 2) % h
    cols = np.arange(-1, w + 2) % w
    padded = np.zeros(((h + 3) * (w + 3), 4), dtype=pixels.dtype)
    padded[:, :3] = pixels[rows][:, cols].reshape(-1, 3)
    padded.setflags(write=False)
    return padded


def _pixel_directions(h: int, w: int, rotation: float, first: int = 0, last: int | None = None,
                      ) -> tuple[np.ndarray, np.ndarray]:
    """World directions of the centres of pixel rows [first, last) of an h x w image (rows*W, 3) and
    their solid angles (rows*W,)."""
    u = (np.arange(w) + 0.5) / w
    v = 1.0 - (np.arange(first, h if last is None else last) + 0.5) / h
    phi = (0.5 - u) * 2.0 * math.pi  # texture azimuth: atan2(y, x) in the texture's frame
    lat = (v - 0.5) * math.pi
    lat, phi = np.meshgrid(lat, phi, indexing="ij")
    t = np.stack([np.cos(lat) * np.cos(phi), np.cos(lat) * np.sin(phi), np.sin(lat)], axis=-1).reshape(-1, 3)
    c, s = math.cos(rotation), math.sin(rotation)
    world = np.stack([c * t[:, 0] + s * t[:, 1], -s * t[:, 0] + c * t[:, 1], t[:, 2]], axis=1)  # R_z(-phi) t
    # The exact solid angle of each pixel's band of latitude: the pixels sum to 4 pi.
    half = 0.5 * math.pi / h
    solid = ((np.sin(lat + half) - np.sin(lat - half)) * (2.0 * math.pi / w)).reshape(-1)
    return world, solid


def _strips(h: int, w: int, starts: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Row ranges covering an h x w image of at most ``world_image.STRIP_PIXELS`` each (at least
    one row), each a run of whole blocks when ``starts`` gives the blocks' first rows: the per-pixel
    temporaries of the sums below stay bounded whatever the image's size."""
    starts = list(range(h)) if starts is None else [int(row) for row in starts]
    per_strip = max(1, world_image.STRIP_PIXELS // w)
    edges, previous = [0], 0
    for row in [*starts[1:], h]:
        if row - edges[-1] > per_strip and previous > edges[-1]:
            edges.append(previous)
        previous = row
    edges.append(h)
    return list(zip(edges[:-1], edges[1:], strict=True))


def _irradiance(pixels: np.ndarray, rotation: float) -> np.ndarray:
    """Irradiance of ``pixels`` at strength 1 at the nodes of the irradiance map (module docstring)."""
    h, w = pixels.shape[:2]
    # Area-average to at most IRRADIANCE_SOURCE: sums of radiance x solid angle.
    cols = np.linspace(0, w, min(w, IRRADIANCE_SOURCE[0]) + 1).astype(np.int64)[:-1]
    rows = np.linspace(0, h, min(h, IRRADIANCE_SOURCE[1]) + 1).astype(np.int64)[:-1]
    powers, directions = [], []
    for first, last in _strips(h, w, rows):  # whole rows of blocks at a time
        d, solid = _pixel_directions(h, w, rotation, first, last)
        weighted = pixels[first:last].reshape(-1, 3).astype(np.float64) * solid[:, None]
        block_rows = rows[(rows >= first) & (rows < last)] - first

        def blocks(a: np.ndarray, block_rows=block_rows, n=last - first) -> np.ndarray:
            a = a.reshape(n, w, -1)
            return np.add.reduceat(np.add.reduceat(a, block_rows, axis=0), cols, axis=1).reshape(-1, a.shape[-1])

        powers.append(blocks(weighted))
        # Each block's light comes from its luminance-weighted mean direction: a sun keeps its place.
        weight = (weighted @ LUMINANCE) + 1e-12 * solid
        directions.append(blocks(d * weight[:, None]))
    power = np.concatenate(powers)
    mean_dir = np.concatenate(directions)
    mean_dir /= np.linalg.norm(mean_dir, axis=1)[:, None]
    lon = -math.pi + np.arange(IRRADIANCE_LON) * (2.0 * math.pi / IRRADIANCE_LON)
    lat = -0.5 * math.pi + np.arange(IRRADIANCE_LAT + 1) * (math.pi / IRRADIANCE_LAT)
    lat, lon = np.meshgrid(lat, lon, indexing="ij")
    normals = np.stack([np.cos(lat) * np.cos(lon), np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1).reshape(-1, 3)
    out = np.empty((len(normals), 3))
    for start in range(0, len(normals), 256):  # bounded memory: 256 normals x the source's directions
        cos = np.maximum(0.0, normals[start:start + 256] @ mean_dir.T)
        out[start:start + 256] = cos @ power
    return out.reshape(IRRADIANCE_LAT + 1, IRRADIANCE_LON, 3)


def _luminance_peak(pixels: np.ndarray) -> float:
    h, w = pixels.shape[:2]
    return max(float((pixels[a:b].reshape(-1, 3).astype(np.float64) @ LUMINANCE).max()) for a, b in _strips(h, w))


def _sun_strips(pixels: np.ndarray):
    """Per strip of rows: (first, last, rgb (n, 3) float64, which pixels are the sun: at least
    ``SUN_FRACTION`` of the brightest luminance)."""
    h, w = pixels.shape[:2]
    strips = _strips(h, w)
    peak = _luminance_peak(pixels) if len(strips) > 1 else None
    for first, last in strips:
        rgb = pixels[first:last].reshape(-1, 3).astype(np.float64)
        lum = rgb @ LUMINANCE
        yield first, last, rgb, lum, lum >= SUN_FRACTION * (lum.max() if peak is None else peak)


def _sun_direction(pixels: np.ndarray, rotation: float) -> np.ndarray:
    h, w = pixels.shape[:2]
    centre = np.zeros(3)
    for first, last, _, lum, sun in _sun_strips(pixels):
        d, solid = _pixel_directions(h, w, rotation, first, last)
        centre += ((lum * solid)[sun, None] * d[sun]).sum(axis=0)
    norm = float(np.linalg.norm(centre))
    return centre / norm if norm > 0 else np.array([0.0, 0.0, 1.0])


def _sun_color(pixels: np.ndarray) -> np.ndarray:
    """The light of the sun pixels, sum(L_c omega) over radiance L and solid angle omega, divided by
    its luminance; negative values (out of gamut in some HDR images) count as 0, and an image without
    light gives white."""
    h, w = pixels.shape[:2]
    # The solid angle of a pixel is its row's band of latitude over its width (the turn does not
    # change it): rows from the top, latitude pi/2 - (i + 1/2) pi/h at the centre.
    lat = 0.5 * np.pi - (np.arange(h) + 0.5) * np.pi / h
    half = 0.5 * np.pi / h
    solid = np.repeat((np.sin(lat + half) - np.sin(lat - half)) * (2.0 * np.pi / w), w)
    light = np.zeros(3)
    for first, last, rgb, _, sun in _sun_strips(pixels):
        light += (rgb[sun] * solid[first * w:last * w][sun, None]).sum(axis=0)
    light = np.maximum(light, 0.0)
    luminance = float(light @ LUMINANCE)
    return light / luminance if luminance > 0.0 else np.ones(3)


def sunless(pixels: np.ndarray) -> np.ndarray:
    """A float32 copy of the image (H, W, 3) without its sun, for a scene whose explicit sun stands
    for it (``light.follow_environment``, docs/model.md §8.18). The sky around the sun is the ring
    from ``SUN_REACH_DEG`` to twice that about the sun's direction (``sun_direction``; at least two
    pixels wide); the sun is the pixels within ``SUN_REACH_DEG`` that are at least ``SUN_EDGE`` of the
    brightest luminance and ``SUN_OVER_SKY`` times the ring's median luminance (its disc and the
    image's blur of it), and they take the ring's median colour. An image without a sun standing out
    of its sky (a uniform or overcast one) is left as it is. The sun's direction and colour are still
    the image's own (``_make_sunless_world``)."""
    h, w = pixels.shape[:2]
    out = np.array(pixels, dtype=np.float32)
    peak = _luminance_peak(pixels)
    if not peak > 0.0:
        return out
    toward = _sun_direction(pixels, 0.0)  # in the image's own frame, whatever the turn
    reach = math.radians(SUN_REACH_DEG)
    outer = reach + max(reach, 4.0 * math.pi / w)
    # Only the rows whose latitude lies within the ring's reach of the sun's (a row is pi / h high).
    latitude = 0.5 * math.pi - (np.arange(h) + 0.5) * math.pi / h
    sun_latitude = math.asin(float(np.clip(toward[2], -1.0, 1.0)))
    rows = np.flatnonzero(np.abs(latitude - sun_latitude) <= outer + math.pi / h)
    first, last = int(rows[0]), int(rows[-1]) + 1
    d, _ = _pixel_directions(h, w, 0.0, first, last)
    cos = (d @ toward).reshape(last - first, w)
    near = cos >= math.cos(reach)
    ring = ~near & (cos >= math.cos(outer))
    if not ring.any():
        return out
    block = out[first:last]
    lum = block.astype(np.float64) @ LUMINANCE
    sun = near & (lum >= SUN_EDGE * peak) & (lum >= SUN_OVER_SKY * float(np.median(lum[ring])))
    block[sun] = np.median(block[ring], axis=0)
    return out


def _sunless_padded(pixels: np.ndarray) -> np.ndarray:
    return _pad(sunless(pixels))


def _make_sunless_world(pixels: np.ndarray, rotation: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``_make_world`` of an image whose sun an explicit sun stands for: the irradiance of the image
    without its sun (``sunless``), the direction and colour of the sun it had."""
    with warnings.catch_warnings(), np.errstate(all="ignore"):  # the pixels are finite and bounded
        warnings.simplefilter("ignore")
        return _irradiance(sunless(pixels), rotation), _sun_direction(pixels, rotation), _sun_color(pixels)


LAYOUT = f"{IRRADIANCE_LON}x{IRRADIANCE_LAT}-{IRRADIANCE_SOURCE[0]}x{IRRADIANCE_SOURCE[1]}-{SUN_FRACTION}"
SUNLESS = f"sunless-{SUN_EDGE}-{SUN_OVER_SKY}-{SUN_REACH_DEG}"  # the cache's tag of an image without its sun


def _make_world(pixels: np.ndarray, rotation: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What ``world_cache`` keeps of an image and turn: irradiance map, sun direction, sun colour."""
    with warnings.catch_warnings(), np.errstate(all="ignore"):  # the pixels are finite and bounded
        warnings.simplefilter("ignore")
        return _irradiance(pixels, rotation), _sun_direction(pixels, rotation), _sun_color(pixels)


def world_bytes(scene: dict) -> int:
    """Bytes the world of a normalised scene's environment holds at its peak while it is made, from
    the image's header (checked: a ``SceneError`` for a bad or too large one); 0 without one."""
    env = scene.get("environment")
    if env is None or env["world"] == "none":
        return 0
    header = world_image.header(image_path(env))
    peak = world_image.peak_bytes(*header)
    if scene.get("light", {}).get("follow_environment", False):  # the image without its sun beside it
        f = world_image.factor_for(header[0], header[1])
        w, h = -(-header[0] // f), -(-header[1] // f)
        peak += w * h * 12 + (w + 3) * (h + 3) * world_image.PADDED_BYTES  # float32 RGB, and padded
    return peak


def from_scene(scene: dict) -> Environment | None:
    """The environment of a normalised scene, or None for the paper's plain background. Where the
    scene's sun follows the environment's, the sun stands for the image's: the image is taken
    without it (``sunless``), so that its light reaches the lamp once (docs/model.md §8.18)."""
    env = scene.get("environment")  # a scene an earlier version built in code has none
    if env is None or env["world"] == "none":
        return None
    rotation = math.radians(env["rotation_deg"])
    if scene.get("light", {}).get("follow_environment", False):
        world = world_cache.world(image_path(env), rotation, f"{LAYOUT}-{SUNLESS}", _make_sunless_world,
                                  (SUNLESS, _sunless_padded))
    else:
        world = world_cache.world(image_path(env), rotation, LAYOUT, _make_world)
    return Environment(world.pixels, float(env["strength"]), rotation, world)
