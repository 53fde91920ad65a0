"""The second estimator of luminous intensity: light traced forward from the bulbs, through the same
optics as the renderer's, into cones of directions (Monte Carlo light tracing).

Independent of ``intensity`` (which integrates the luminance of rendered views) in what it samples
and how: here the light's power leaves the sources and is counted where it leaves the lamp. What it
shares with the renderer is the optics a ray meets — the parts' intersections (``walk.intersect``),
the Fresnel split per band and polarisation (``surfaces.at_dielectric``, ``at_plate_face``), the
Beer–Lambert absorption (``optics.absorption``), the law of reflection — since both must describe the
same lamp; the sources, the light's transport and the counting are written here.

The sources of the photometric model (``raytrace.spectral``), each sampled by its own emission:

- the bulb, a Lambertian sphere of radiance L(λ) and radius r: flux Φ(λ) = π L · 4π r²; a photon
  starts at a uniform point of the sphere in a cosine-distributed direction about its normal
  (the normal plus a uniform unit vector, normalised), carrying Φ / N;
- the LED dies (a lamp lit by LEDs has no bulb and no glow): flat, of radiance L_0(λ) f(θ, φ)
  (``parts.led_die.emitted``); a photon starts at a uniform point of a die in a cosine-distributed
  direction about its normal, carrying π L_0 f A_dies / N;
- the reflector's glow, which the renderer adds at every reflector hit as a radiance
  L_g(x, ω) = ρ(λ) s (n + 8)/(8π) cos^n β · Ω_b(x) cos θ_b · L(λ) (``surfaces.at_reflector`` and
  ``bulb_irradiance``: the glow share s on the normalised Blinn lobe of the bulb's irradiance): a
  second source, sampled at uniform points of the reflector's projected annulus (from the socket
  to the rim; dA = √(1 + (r/2f)²) dA_proj) in cosine-distributed directions, carrying
  π L_g(x, ω) A_proj √(1 + (r/2f)²) / N.

At the reflector the light is mirrored with k × ρ(λ)(1 − s) (its glow share is the second source);
the bulb, the socket, the lens side wall and a prism plate's housing absorb; light leaving the outer
face of a lens has left the lamp. A branch is dropped below the renderer's cut-off (k < 10⁻³,
``rays.CUTOFF``), k being the light's attenuation since it left its source.

Counting: the flux that leaves within a cone of half angle α about d is F; I(d) ≈ F / Ω(α),
Ω = 2π (1 − cos α): the mean intensity over the cone (a bias of order α² times the curvature of I).
The standard error follows from the spread of the per-photon contributions c_i (all branches of one
source sample summed): Var F = N/(N − 1) (Σ c_i² − (Σ c_i)² / N).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from ..raytrace import optics
from ..raytrace import paths as P
from ..raytrace.engine import make_context
from ..raytrace.engine.context import Context
from ..raytrace.engine.rays import CUTOFF, NOT_DEFERRED, UNRECORDED, Rays, concat
from ..raytrace.engine.surfaces import at_dielectric, at_plate_face, bulb_irradiance
from ..raytrace.engine.walk import depth_limit, intersect, normals_at
from ..raytrace.optics import cosine_directions, uniform_sphere
from ..raytrace.parts import led_die
from ..raytrace.parts.base import put_rows, rows
from ..raytrace.parts.reflector import reflector_normal
from ..scene.reading import SceneError
from .directions import cone_solid_angle, direction
from .intensity import Intensity, measurement_scene

if TYPE_CHECKING:
    from ..freeform.design import DesignMeshes

DEFAULT_CONE_DEG = 3.0
DEFAULT_PHOTONS = 400_000  # per lamp and source
BATCH = 50_000


@dataclass
class Tally:
    """Per direction: the flux counted so far (Y, lm; and X, Y, Z), its variance from the sources
    finished, and for the source being sampled the sums of its samples' contributions c and c²."""

    total_y: np.ndarray
    total_xyz: np.ndarray
    variance: np.ndarray
    sum_y: np.ndarray
    sum_y2: np.ndarray

    @classmethod
    def empty(cls, n: int) -> Tally:
        return cls(np.zeros(n), np.zeros((n, 3)), np.zeros(n), np.zeros(n), np.zeros(n))

    def close_source(self, samples: int) -> None:
        """The sums of one source of ``samples`` samples added to the totals, with their variance
        N/(N − 1) (Σ c² − (Σ c)² / N)."""
        if samples > 1:
            self.variance += np.maximum((self.sum_y2 - self.sum_y**2 / samples) * samples / (samples - 1), 0.0)
        self.total_y += self.sum_y
        self.sum_y[:] = 0.0
        self.sum_y2[:] = 0.0


def _rays(lamp: int, o: np.ndarray, d: np.ndarray, k: int, src: int) -> Rays:
    n = len(o)
    ones = np.ones((n, k))
    return Rays(pix=np.arange(n), lamp=np.full(n, lamp), o=o, d=d, k=ones, medium=np.full(n, P.IN_AIR, np.int8),
                src=np.full(n, src, np.int8), parent=UNRECORDED, branch=UNRECORDED, seen_reflector=np.zeros(n, bool),
                k_s=0.5 * ones, travelled=NOT_DEFERRED)  # unpolarised light: half of it s-polarised


def bulb_photons(ctx: Context, lamp: int, n: int, rng: np.random.Generator) -> tuple[Rays, np.ndarray]:
    """``n`` photons from the bulb of ``lamp`` (lamp frame) and their flux per band (n, K), W/nm."""
    lamps = ctx.lamps
    radius = float(lamps.bulb_radius[lamp])
    normal = uniform_sphere(n, rng)
    o = lamps.bulb_center[lamp] + radius * normal
    d = cosine_directions(normal, rng)
    radiance = lamps.bulb_radiance[lamp]
    flux = math.pi * radiance * 4.0 * math.pi * (radius * 1e-3) ** 2  # Φ(λ) = π L · 4π r², r in m
    # The back of the bulb inside the socket (which runs from the vertex to the bulb's centre plane)
    # sends no light: its samples count, with nothing traced.
    socket = float(lamps.socket_radius[lamp])
    free = np.nonzero((np.hypot(o[:, 0], o[:, 2]) >= socket) | (o[:, 1] <= lamps.bulb_center[lamp, 1]))[0]
    rays = _rays(lamp, o, d, ctx.channels, P.BULB).take(free)
    rays.pix = free
    return rays, np.broadcast_to(flux / n, (n, ctx.channels))


def led_photons(ctx: Context, lamp: int, n: int, rng: np.random.Generator) -> tuple[Rays, np.ndarray] | None:
    """``n`` photons from the LED dies of ``lamp`` (lamp frame) and their flux per band (n, K), W/nm;
    None for a lamp lit by its bulb. A photon leaves a uniform point of a uniformly chosen die in a
    cosine-distributed direction about its normal, carrying Φ_dies(λ) f(θ, φ) / N: the radiance
    L_0(λ) f(θ, φ) of ``parts.led_die.emitted`` sampled with the pdf cos θ / π, so that the flux is
    π L_0 A per die whatever the pattern (f's mean over that pdf is 1, ``photometry.far_field``).
    A guide lit at both ends (``GuideTable.both_ends``) has the array's mirror image too, with the same
    flux: every other photon is reflected through the guide's middle, each carrying twice as much."""
    lamps = ctx.lamps
    columns, rows_ = int(lamps.led_columns[lamp]), int(lamps.led_rows[lamp])
    if columns == 0:
        return None
    half, pitch = lamps.led_half[lamp], lamps.led_pitch[lamp]
    across, up, normal = lamps.led_across[lamp], lamps.led_up[lamp], lamps.led_normal[lamp]
    i = rng.integers(0, columns, n) - (columns - 1) / 2.0
    j = rng.integers(0, rows_, n) - (rows_ - 1) / 2.0
    a = i * pitch[0] + rng.uniform(-half[0], half[0], n)
    b = j * pitch[1] + rng.uniform(-half[1], half[1], n)
    o = lamps.led_center[lamp] + a[:, None] * across + b[:, None] * up
    index = np.full(n, lamp)
    d = cosine_directions(np.broadcast_to(normal, (n, 3)), rng)
    area = columns * rows_ * 4.0 * half[0] * half[1] * 1e-6  # m²
    radiance = led_die.emitted(lamps, index, -d)  # the luminance seen looking back along the light
    arrays = 1
    if lamps.guide is not None and lamps.guide.both_ends[lamp]:
        arrays, image = 2, np.arange(1, n, 2)
        o_m, d_m = lamps.guide.mirror(o.take(image, axis=0), d.take(image, axis=0), index.take(image))
        o[image], d[image] = o_m, d_m
    return _rays(lamp, o, d, ctx.channels, P.LED), radiance * (math.pi * area * arrays / n)


def glow_photons(ctx: Context, lamp: int, n: int, rng: np.random.Generator) -> tuple[Rays, np.ndarray] | None:
    """``n`` samples of the reflector's glow of ``lamp`` and their flux per band (n, K); None where
    the lamp has no reflector (a prism plate) or no glow."""
    lamps = ctx.lamps
    focal, vertex, rim = float(lamps.focal[lamp]), float(lamps.vertex[lamp]), float(lamps.rim[lamp])
    scatter = float(lamps.scatter[lamp])
    if not math.isfinite(rim) or scatter <= 0.0:
        return None
    inner = float(lamps.socket_radius[lamp])
    outer = math.sqrt(max(0.0, 4.0 * focal * (vertex - rim)))  # the rim's radius
    if outer <= inner:
        return None
    radial = np.sqrt(inner**2 + rng.uniform(0.0, 1.0, n) * (outer**2 - inner**2))
    phi = rng.uniform(0.0, 2.0 * math.pi, n)
    hit = np.stack([radial * np.cos(phi), vertex - radial**2 / (4.0 * focal), radial * np.sin(phi)], axis=1)
    index = np.full(n, lamp)
    normal = reflector_normal(hit, lamps.focal.take(index))
    d = cosine_directions(normal, rng)
    to_bulb = optics.normalize(lamps.bulb_center[lamp] - hit)
    lobe = optics.blinn(normal, d, to_bulb, scatter, float(lamps.scatter_shininess[lamp]))
    irradiance = bulb_irradiance(to_bulb, normal, hit, lamps, index)
    area = math.pi * (outer**2 - inner**2) * 1e-6  # m²
    jacobian = np.sqrt(1.0 + (radial / (2.0 * focal)) ** 2)
    radiance = lamps.reflector_bands[lamp] * lamps.bulb_radiance[lamp]  # ρ(λ) L(λ)
    flux = (math.pi * area / n) * (lobe * irradiance * jacobian)[:, None] * radiance
    return _rays(lamp, hit, d, ctx.channels, P.REFLECTOR), flux


def trace(ctx: Context, rays: Rays) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Follow light ``rays`` (lamp frame) through the lamp until it is absorbed, lost or leaves:
    the source sample (``pix``), direction and attenuation (per band) of every branch that leaves."""
    lamps = ctx.lamps
    out_pix, out_d, out_k = [], [], []
    depth = 0
    while len(rays) and depth < depth_limit(ctx):  # a light guide's paths are walked deeper
        depth += 1
        t, surface, normals = intersect(ctx, rays)
        rays = _absorbed(ctx, rays, t)
        children: list[Rays] = []
        met = np.nonzero(surface == P.REFLECTOR)[0]
        if len(met):
            d, hit = _end_points(rays, t, met)
            lamp = rays.lamp.take(met)
            mirror = rows(lamps.reflector_bands, lamp) * lamps.reflectance.take(lamp)[:, None]  # ρ(λ)(1 − s)
            k, k_s = rows(rays.k, met) * mirror, rows(rays.k_s, met) * mirror
            going = np.nonzero(k.max(axis=1) >= CUTOFF)[0]
            normal = reflector_normal(rows(hit, going), lamps.focal.take(lamp.take(going)))
            children.append(Rays(pix=rays.pix.take(met).take(going), lamp=lamp.take(going), o=rows(hit, going),
                                 d=optics.reflect(rows(d, going), normal), k=rows(k, going),
                                 medium=np.full(len(going), P.IN_AIR, np.int8),
                                 src=np.full(len(going), P.REFLECTOR, np.int8), parent=UNRECORDED,
                                 branch=UNRECORDED, seen_reflector=np.ones(len(going), bool), k_s=rows(k_s, going),
                                 travelled=NOT_DEFERRED))
        met = np.nonzero((surface == P.OUTER) | (surface == P.CUT))[0]
        if len(met):
            d, hit = _end_points(rays, t, met)
            faces = surface.take(met)
            face = at_dielectric(rays, met, rows(rays.k, met), d, hit, UNRECORDED, faces,
                                 normals_at(normals, met, faces), lamps.ior, P.IN_LENS, lamps.ior_bands)
            partial = face.split.partial
            alive = face.split.transmitted.max(axis=1) >= CUTOFF
            leaving = np.nonzero(partial & (faces == P.OUTER) & face.from_inside)[0]
            if len(leaving):
                gone = face.through(leaving)
                out_pix.append(gone.pix)
                out_d.append(gone.d)
                out_k.append(gone.k)
            children.append(face.reflected())
            inner = np.nonzero(partial & (faces != P.OUTER) & alive)[0]
            if len(inner):
                children.append(face.through(inner))
        # the lamp's second dielectric: a prism plate's faces or a light guide's rod
        second = (surface == P.PLATE_FRONT) | (surface == P.RINGS) | (surface == P.GUIDE) if ctx.plates else None
        met = np.nonzero(second)[0] if ctx.plates else ()
        if len(met):
            d, hit = _end_points(rays, t, met)
            faces = surface.take(met)
            children.extend(at_plate_face(rays, met, rows(rays.k, met), d, hit, UNRECORDED, faces,
                                          normals_at(normals, met, faces), lamps))
        # the bulb, the socket, the side wall, the housing absorb; nothing met: lost inside the body
        children = [c for c in children if len(c)]
        rays = concat(children) if len(children) > 1 else (children[0] if children else rays.take(np.zeros(0, int)))
    if not out_pix:
        return np.zeros(0, int), np.zeros((0, 3)), np.zeros((0, ctx.channels))
    return np.concatenate(out_pix), np.concatenate(out_d), np.concatenate(out_k)


def _absorbed(ctx: Context, rays: Rays, t: np.ndarray) -> Rays:
    """Beer–Lambert along the segments inside a lens or a prism plate (eq. 2), on k and its s share."""
    lamps = ctx.lamps
    k, k_s = rays.k.copy(), rays.k_s.copy()
    for medium, coefficients in ((P.IN_LENS, lamps.absorption), (P.IN_PLATE, lamps.plate_absorption)):
        inside = np.nonzero(rays.medium == medium)[0]
        if len(inside):
            transmittance = optics.absorption(rows(coefficients, rays.lamp.take(inside)), t.take(inside))
            put_rows(k, inside, rows(k, inside) * transmittance)
            put_rows(k_s, inside, rows(k_s, inside) * transmittance)
    return replace(rays, k=k, k_s=k_s)


def _end_points(rays: Rays, t: np.ndarray, met: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d = rows(rays.d, met)
    return d, rows(rays.o, met) + d * t.take(met)[:, None]


def traced_intensities(scene: dict, angles: Sequence[tuple[float, float]],
                       groups: Sequence[Sequence[int]] | None = None, *, photons: int = DEFAULT_PHOTONS,
                       cone_deg: float = DEFAULT_CONE_DEG, seed: int = 0, bands: int | None = None,
                       batch: int = BATCH, meshes: DesignMeshes | None = None) -> list[list[Intensity]]:
    """I(H, V) in cd at each of ``angles`` for each group of lamps (None: the whole design), as the
    mean over a cone of half angle ``cone_deg``, from ``photons`` samples of each source of each lit
    lamp: ``result[group][direction]``. A free-form design is traced on its ``meshes``, as one lamp."""
    return traced_beam(scene, angles, groups, photons=photons, cone_deg=cone_deg, seed=seed, bands=bands,
                       batch=batch, meshes=meshes)[0]


def traced_beam(scene: dict, angles: Sequence[tuple[float, float]],
                groups: Sequence[Sequence[int]] | None = None, *, photons: int = DEFAULT_PHOTONS,
                cone_deg: float = DEFAULT_CONE_DEG, seed: int = 0, bands: int | None = None,
                batch: int = BATCH, meshes: DesignMeshes | None = None
                ) -> tuple[list[list[Intensity]], list[tuple[float, float]]]:
    """``traced_intensities`` and, from the same photons, each group's luminous flux leaving the lamp
    in every direction (lm) with its standard error: ``(intensities, [(lm, stderr) per group])``."""
    if photons < 2:
        raise ValueError(f"photons: {photons!r} is not 2 or more")
    if not 0.0 < cone_deg < 90.0:
        raise ValueError(f"cone: {cone_deg!r} degrees is not between 0 and 90")
    targets = np.array([direction(h, v) for h, v in angles])
    solid = cone_solid_angle(cone_deg)
    rng = np.random.default_rng(seed)
    measured = measurement_scene(scene)
    if "freeform" in scene:  # its meshes, one lamp: the sources and the walk of ``freeform.light_tracing``
        if meshes is None or groups not in (None, [[0]]):
            raise SceneError("freeform", "a free-form design is light-traced on its meshes, as one lamp; allowed "
                                         "its meshes (DesignMeshes) and no lamp groups")
        from ..freeform import light_tracing as mesh_light

        ctx = mesh_light.context(measured, meshes, bands)
        counted = _counted(mesh_light.sources(ctx, measured), lambda rays: mesh_light.trace(ctx, rays), targets,
                           math.cos(math.radians(cone_deg)), ctx.photometric.to_xyz, photons, batch, rng)
        return _grouped([[0]], {0: counted}, solid, len(targets))
    ctx = make_context(measured, 1, 1, bands=bands)
    if ctx.walker is not None or ctx.lamps.any_cylindrical:
        raise SceneError("lamps", "light tracing follows flat-lensed parametric lamps; allowed lamps without "
                                  "cylindrical lenses")
    groups = [list(range(len(scene["lamps"])))] if groups is None else [list(g) for g in groups]
    per_lamp: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
    for lamp in sorted({i for g in groups for i in g}):
        if not (ctx.lamps.bulb_radiance[lamp].any() or ctx.lamps.led_radiance[lamp].any()):
            columns = len(targets) + 1
            per_lamp[lamp] = (np.zeros(columns), np.zeros(columns), np.zeros((columns, 3)))
            continue
        emitters = (bulb_photons, glow_photons) if ctx.lamps.has_bulb[lamp] else (led_photons,)
        emit = [lambda n, rng, source=source, lamp=lamp: source(ctx, lamp, n, rng) for source in emitters]
        per_lamp[lamp] = _counted(emit, lambda rays: trace(ctx, rays), targets, math.cos(math.radians(cone_deg)),
                                  ctx.photometric.to_xyz, photons, batch, rng)
    return _grouped(groups, per_lamp, solid, len(targets))


def _counted(sources: Sequence, follow, targets: np.ndarray, cos_cone: float, to_xyz: np.ndarray, photons: int,
             batch: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Y, its variance, X Y Z) of the flux leaving within each cone about ``targets`` and, last, in every
    direction, from ``photons`` samples of each source (``source(n, rng)`` -> rays and their flux per
    band, or None for no light), each followed out of the lamp by ``follow``."""
    columns = len(targets) + 1  # the last counts every branch that leaves: the flux out
    tally = Tally.empty(columns)
    for source in sources:
        done = 0
        while done < photons:
            n = min(batch, photons - done)
            emitted = source(n, rng)
            if emitted is None:
                break
            rays, flux = emitted
            # the flux of the batch as a share of the source's whole sample: n / photons
            pix, d, k = follow(rays)
            xyz = (k * rows(flux, pix) * (n / photons)) @ to_xyz  # lm per branch
            inside = np.hstack([(d @ targets.T) >= cos_cone, np.ones((len(d), 1), bool)])  # (E, directions + 1)
            for j in range(columns):
                sel = np.nonzero(inside[:, j])[0]
                c = np.bincount(pix.take(sel), weights=xyz[sel, 1], minlength=n)
                tally.sum_y[j] += c.sum()
                tally.sum_y2[j] += (c * c).sum()
                tally.total_xyz[j] += xyz[sel].sum(axis=0)
            done += n
        if done:
            tally.close_source(done)
    return tally.total_y, tally.variance, tally.total_xyz


def _grouped(groups: Sequence[Sequence[int]], per_lamp: dict, solid: float, directions: int
             ) -> tuple[list[list[Intensity]], list[tuple[float, float]]]:
    result, flux = [], []
    for group in groups:
        y = sum(per_lamp[i][0] for i in group)
        var = sum(per_lamp[i][1] for i in group)
        xyz = sum(per_lamp[i][2] for i in group)
        result.append([Intensity(float(y[j] / solid), float(math.sqrt(var[j]) / solid), xyz[j] / solid)
                       for j in range(directions)])
        flux.append((float(y[-1]), float(math.sqrt(var[-1]))))
    return result, flux


def traced_intensity(scene: dict, h_deg: float, v_deg: float, lamps: Sequence[int] | None = None,
                     **options) -> Intensity:
    """``traced_intensities`` at one direction, for one group of lamps (None: the whole design)."""
    return traced_intensities(scene, [(h_deg, v_deg)], None if lamps is None else [lamps], **options)[0][0]
