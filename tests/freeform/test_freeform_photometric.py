"""Free-form parts in the photometric mode (docs/photometric.md, "Free-form parts"), against closed
forms: a bulb mesh's luminance Φ/(πA) (or the sphere's it stands for, Φ/(4π² r²)) and the slab series
per wavelength band through a clear lens mesh, a filter read from a measured curve beside the document;
and the role values each mode takes."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import slab_series
from needs import require

from core_tracer.freeform import render_passes, shapes
from core_tracer.photometry import materials
from core_tracer.photometry.cie import xyz_matrix
from core_tracer.raytrace import spectral
from core_tracer.raytrace.engine.rays import CUTOFF
from core_tracer.scene import beside
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene

require("embreex")

FLUX = 440.0
RADIUS = 8.0


def design(parts: list[dict], meshes: list, width: float = 4.0) -> tuple[dict, dict]:
    """A photometric free-form design seen straight on by an orthographic camera, in the dark."""
    doc = {"schema": "lamp-scene/2", "light_model": "photometric", "lamps": [{}],
           "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                      "width": width, "exposure": "ev100", "ev100": 10.0},
           "light": {"illuminance_lux": 0.0},
           "image": {"width": 5, "height": 5},
           "freeform": {"mesh_file": "design.glb", "parts": parts}}
    return parse_scene(doc), {m.name: m for m in meshes}


def bulb(**values) -> dict:
    return {"object": "Bulb", "role": "bulb", "bulb": {"type": "custom", "flux_lm": FLUX, "spectrum": "incandescent",
                                                       **values}}


def mesh_area(mesh) -> float:
    c = mesh.vertices[mesh.triangles]
    return float(0.5 * np.linalg.norm(np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]), axis=1).sum())


@pytest.mark.parametrize("radius", [0.0, RADIUS])
def test_a_bare_bulb_mesh_has_the_luminance_of_its_flux_over_its_area(radius):
    """L = Φ / (π A): A the mesh's area (radius 0), or the sphere's it stands for, 4π r² (a converted bulb)."""
    sphere = shapes.uv_sphere("Bulb", (0.0, 40.0, 0.0), RADIUS, segments=48)
    scene, meshes = design([bulb(radius=radius)], [sphere])
    result = render_passes(scene, meshes)
    area_m2 = (4.0 * math.pi * radius**2 if radius else mesh_area(sphere)) * 1e-6
    expected = FLUX / (math.pi * area_m2)
    assert result.stats["light_model"] == "photometric" and result.stats["bands"] == spectral.DEFAULT_BANDS
    np.testing.assert_allclose(result.image[:, :, 1], expected, rtol=1e-5)
    np.testing.assert_allclose(result.passes["bulb"][:, :, 1], expected, rtol=1e-5)
    if radius:
        assert mesh_area(sphere) < 4.0 * math.pi * radius**2  # the tessellation is a little smaller


def slab(thickness: float, lens: dict) -> tuple[dict, dict]:
    meshes = [shapes.box("Slab", (-30, 0, -30), (30, thickness, 30)), shapes.box("Bulb", (-60, 20, -60), (60, 30, 60))]
    parts = [{"object": "Slab", "role": "lens", "lens": {"specular": 0.0, "material": "pmma", **lens}},
             bulb(radius=0.0)]
    return design(parts, meshes)


def expected_through_slab(scene: dict, meshes: dict, transmittance: np.ndarray) -> np.ndarray:
    """X, Y, Z of the bulb wall seen through the slab: per band, the slab series of n(λ) (normal
    incidence: s and p alike) with the internal ``transmittance``, walked with the cut-off on the
    largest band, times the wall's radiance."""
    bands = spectral.bands_of(None)
    lens = scene["freeform"]["parts"][0]["lens"]
    n = materials.refractive_index(*spectral.index_of(lens), bands.centres_nm)
    r = ((n - 1.0) / (n + 1.0)) ** 2
    flux, spectrum = spectral.bulb_spectrum(scene["freeform"]["parts"][1]["bulb"], "bulb")
    area = mesh_area(meshes["Bulb"])
    radiance = spectral.sources.bulb_spectral_radiance(flux, spectrum, math.sqrt(area / (4 * math.pi)), bands)
    return (radiance * slab_series(r, transmittance, CUTOFF)) @ xyz_matrix(bands)


def test_the_bulb_through_a_clear_slab_mesh_is_the_slab_series_per_band():
    scene, meshes = slab(3.0, {"filter": "clear"})
    bands = spectral.bands_of(None)
    transmittance = spectral.filter_transmittance(scene["freeform"]["parts"][0]["lens"], bands, "lens")
    centre = render_passes(scene, meshes).image[2, 2]
    np.testing.assert_allclose(centre, expected_through_slab(scene, meshes, transmittance), rtol=2e-5)


def test_a_filter_file_beside_the_document_colours_the_slab_by_beer_lambert(tmp_path):
    """A measured filter curve (``filter_file``) at 3 mm, the slab 4.5 mm: T(λ)^(4.5/3) per band."""
    nm = np.arange(380.0, 781.0, 5.0)
    curve = 0.02 + 0.9 / (1.0 + np.exp(-(nm - 600.0) / 8.0))
    (tmp_path / "red.csv").write_text("nm,transmittance\n" + "".join(f"{a:g},{b:.6f}\n" for a, b in zip(nm, curve,
                                                                                                      strict=True)))
    scene, meshes = slab(4.5, {"filter": "file", "filter_file": "red.csv", "filter_thickness": 3.0})
    with pytest.raises(SceneError, match="given when the document is loaded"):
        render_passes(scene, meshes)  # a bare name: never looked up in the working directory
    traced = beside.with_spectrum_files(tmp_path / "design.json", scene)
    assert traced["freeform"]["parts"][0]["lens"]["filter_file"] == str(tmp_path / "red.csv")
    assert scene["freeform"]["parts"][0]["lens"]["filter_file"] == "red.csv"  # the scene itself unchanged
    bands = spectral.bands_of(None)
    at_3mm = spectral.filter_transmittance(traced["freeform"]["parts"][0]["lens"], bands, "lens")
    centre = render_passes(traced, meshes).image[2, 2]
    np.testing.assert_allclose(centre, expected_through_slab(scene, meshes, at_3mm ** 1.5), rtol=2e-5)
    assert centre[0] > 2.0 * centre[2]  # red


def test_file_fields_their_kind_does_not_read_are_refused_in_one_line():
    scene, _ = slab(3.0, {"filter": "clear"})
    doc = {**scene, "freeform": {**scene["freeform"]}}
    doc["freeform"]["parts"] = [{**doc["freeform"]["parts"][0],
                                 "lens": {**doc["freeform"]["parts"][0]["lens"], "filter_file": "red.csv"}},
                                doc["freeform"]["parts"][1]]
    with pytest.raises(SceneError) as err:
        parse_scene(doc)
    assert err.value.path == "freeform.parts[0].lens.filter_file" and '"clear"' in str(err.value)
    doc["freeform"]["parts"] = [scene["freeform"]["parts"][0], bulb(spectrum="led", spectrum_file="led.csv")]
    with pytest.raises(SceneError) as err:
        parse_scene(doc)
    assert err.value.path == "freeform.parts[1].bulb.spectrum_file" and "\n" not in str(err.value)


@pytest.mark.slow
def test_a_free_form_design_is_measured_on_its_meshes_by_both_estimators():
    """Rendered views and forward light tracing measure the meshes (a bare bulb mesh: I = L · its
    projected area, Φ/(4π) for a convex Lambertian emitter; every photon leaves: the flux out is Φ);
    light tracing without the meshes refuses in one line rather than count the parametric lamps' light."""
    from core_tracer.freeform.design import DesignMeshes
    from core_tracer.measures import intensity, light_tracing

    sphere = shapes.uv_sphere("Bulb", (0.0, 40.0, 0.0), RADIUS, segments=64)
    scene, meshes = design([bulb(radius=0.0)], [sphere])
    scene["body"] = {**scene["body"], "size": [30.0, 30.0], "depth": 60.0}
    measured = intensity.rendered_intensity(scene, 0.0, 0.0, pixel_mm=0.25, replicates=4,
                                            meshes=DesignMeshes(meshes))
    # a convex Lambertian emitter of flux Φ = π L A: I = L A/4 = Φ/(4π) in every direction (its projected
    # area a quarter of its surface, averaged over directions: Cauchy's formula; a fine sphere's in each)
    assert measured.cd == pytest.approx(FLUX / (4.0 * math.pi), rel=0.005)
    (traced,), ((lm, lm_error),) = light_tracing.traced_beam(scene, [(0.0, 0.0), (30.0, 10.0)], photons=100_000,
                                                             cone_deg=10.0, meshes=DesignMeshes(meshes))
    assert lm == pytest.approx(FLUX, rel=1e-9) and lm_error < 1e-6 * FLUX
    for value in traced:  # within 4 standard errors (about 4 % each)
        assert abs(value.cd - FLUX / (4.0 * math.pi)) < 4.0 * value.stderr, (value.cd, value.stderr)
    with pytest.raises(SceneError) as err:
        light_tracing.traced_intensity(scene, 0.0, 0.0, photons=100)
    assert err.value.path == "freeform" and "\n" not in str(err.value)


@pytest.mark.slow
def test_light_tracing_a_free_form_lamp_agrees_with_its_rendered_views():
    """A lamp of meshes (a red PMMA box lens, an aluminised paraboloid with its 10 % glow, a bulb at its
    focus, a socket): I at H-V and at H 10°, V 5° by forward light tracing (its own sources: the bulb
    mesh and the reflector's glow; the renderer's walk) and by rendered views (0.5 mm, 2 replicates) agree
    within 3 combined standard errors plus 2 % (the traced value is the mean over a 3° cone). Measured:
    167.7 ± 2.5 against 168.9 cd and 127.0 ± 2.2 against 127.8 cd at 200 000 photons a source."""
    from test_freeform_files import lamp_meshes

    from core_tracer.freeform.design import DesignMeshes
    from core_tracer.measures import intensity, light_tracing

    parts = [{"object": "Lens", "role": "lens", "lens": {"material": "pmma", "filter": "red"}},
             {"object": "Reflector", "role": "reflector", "reflector": {"finish": "aluminised", "scatter_share": 0.1}},
             bulb(), {"object": "Socket", "role": "socket"}]
    scene, meshes = design(parts, [m for m in lamp_meshes() if m.name != "Body"])
    scene["body"] = {**scene["body"], "size": [110.0, 110.0], "depth": 80.0}
    lamp = DesignMeshes(meshes)
    directions = [(0.0, 0.0), (10.0, 5.0)]
    (traced,), ((lm, _),) = light_tracing.traced_beam(scene, directions, photons=60_000, meshes=lamp)
    assert 0.05 * FLUX < lm < FLUX  # a red filter passes a small share of an incandescent bulb's lumens
    for (h, v), value in zip(directions, traced, strict=True):
        rendered = intensity.rendered_intensity(scene, h, v, pixel_mm=0.5, replicates=2, meshes=lamp)
        allowed = 3.0 * math.hypot(value.stderr, rendered.stderr) + 0.02 * rendered.cd
        print(f"H {h:g} V {v:g}: traced {value.cd:.2f} ± {value.stderr:.2f} cd, rendered {rendered.cd:.2f} "
              f"± {rendered.stderr:.2f} cd")
        assert abs(value.cd - rendered.cd) < allowed, (h, v, value.cd, rendered.cd, allowed)
