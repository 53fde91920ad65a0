"""The photometric report's measures as objectives and constraints: their one-line errors, their
figures against the measures package's own, a search that finds a dense sweep's best homogeneity
with a fifth of its renders, CMA-ES, constraints no design can meet, and the workers' memory
checked on real local Dask clusters."""

from __future__ import annotations

import json

import numpy as np
import optuna
import pytest
from distributed import get_task_stream
from helpers import BASELINE, ROOT, run_cli, small_and_large_worker

from core_tracer.cluster import engine
from core_tracer.cluster.cache import CellCache
from core_tracer.cluster.cells import Inputs, make_cell
from core_tracer.measures import intensity as I
from core_tracer.measures.directions import direction
from core_tracer.measures.homogeneity import homogeneity
from core_tracer.measures.light_tracing import traced_intensity
from core_tracer.optimise import photometric as P
from core_tracer.optimise import search, spec, storage
from core_tracer.optimise import trials as T
from core_tracer.optimise.measures import MEASURES
from core_tracer.scene.reading import SceneError, read_json

STOP = ROOT / "presets" / "photometric-stop-lamp.json"
TAIL = ROOT / "presets" / "photometric-tail-lamp.json"
OFFSET = "bulb.offset[1]"  # the bulb along the lamp's axis (toward the lens: negative)


def opt_doc(tmp_path, **edits) -> dict:
    doc = {"schema": spec.SCHEMA, "base": read_json(str(STOP)),  # a base file is confined to the file's folder
           "parameters": [{"parameter": OFFSET, "range": [-2.0, 4.0]}],
           "objectives": [{"measure": "luminance_cv", "pixel_mm": 2.0}],
           "size": [16, 16], "trials": 10, "seed": 0, "storage": "sqlite:///opt.db"}
    doc.update(edits)
    return doc


def figures_of(opt, values):
    scene = opt.scene_of(values)
    _, _, figures = T.run_trial(make_cell(scene, *opt.size, Inputs()), None, None, False, opt.request)
    return scene, figures


# ---------------------------------------------------------------------------------------------
# The file


def test_every_measure_has_a_goal_a_unit_and_words():
    for name in ("lmin_over_lmax", "lmin_over_lmean", "luminance_cv", "dark_fraction", "grid_min_margin",
                 "colour_distance", "intensity_hv", "total_flux", "lens_thickness"):
        m = MEASURES[name]
        assert m.goal in spec.GOALS and m.description and isinstance(m.unit, str)
    assert MEASURES["luminance_cv"].goal == "minimise" and MEASURES["grid_min_margin"].goal == "maximise"
    assert MEASURES["intensity_hv"].unit == "cd" and MEASURES["total_flux"].unit == "lm"


@pytest.mark.parametrize("edit, where, allowed", [
    ({"objectives": [{"measure": "evenness"}]}, "objectives[0].measure", "luminance_cv"),
    ({"base": read_json(str(BASELINE)), "parameters": [{"parameter": "cuts.height", "range": [0.5, 2.0]}]},
     "objectives[0].measure", 'light_model "photometric"'),
    ({"constraints": [{"measure": "grid_min_margin", "function": "fog", "min": 0}]}, "constraints[0].function",
     "tail, stop, turn, reversing"),
    ({"constraints": [{"measure": "grid_min_margin", "photons": 10, "min": 0}]}, "constraints[0].photons",
     "1000 to"),
    ({"objectives": [{"measure": "luminance_cv", "pixel_mm": 0}]}, "objectives[0].pixel_mm", "0.1 to 10"),
    ({"parameters": [{"parameter": "light_model", "values": ["paper", "photometric"]}]}, "parameters[0].parameter",
     "any other parameter"),
    ({"objectives": [{"measure": "colour_distance", "regulation": "JIS"}]}, "objectives[0].regulation",
     "UN R48, SAE J578"),
    ({"sampler": "cmaes", "constraints": [{"measure": "intensity_hv", "min": 60}]}, "sampler", "with constraints"),
    ({"sampler": "cmaes", "objectives": [{"measure": "luminance_cv"}, {"measure": "lens_thickness"}]}, "sampler",
     "nsga2"),
    ({"sampler": "cmaes", "parameters": [{"parameter": "cuts.type", "values": ["fisheye", "flutes"]}]}, "sampler",
     "ranges only"),
])
def test_bad_input_is_one_error_naming_the_json_path(tmp_path, edit, where, allowed):
    with pytest.raises(SceneError) as e:
        spec.from_doc(opt_doc(tmp_path, **edit), str(tmp_path))
    assert e.value.path == where and allowed in e.value.message and "allowed" in e.value.message
    assert "\n" not in e.value.message


@pytest.mark.slow
def test_a_paper_design_asking_for_a_photometric_measure_is_one_line_from_the_cli(tmp_path):
    path = tmp_path / "opt.json"
    path.write_text(json.dumps(opt_doc(tmp_path, base=read_json(str(BASELINE)),
                                       parameters=[{"parameter": "cuts.height", "range": [0.5, 2.0]}])))
    proc = run_cli("optimise", path, "--workers", "0")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert "opt.json: objectives[0].measure: luminance_cv needs light in cd" in proc.stderr


# ---------------------------------------------------------------------------------------------
# The figures


@pytest.mark.slow
def test_the_trials_homogeneity_is_the_measures_packages_on_the_same_view(tmp_path):
    opt = spec.from_doc(opt_doc(tmp_path, objectives=[{"measure": m, "pixel_mm": 2.0} for m in
                                                      ("lmin_over_lmax", "lmin_over_lmean", "luminance_cv",
                                                       "dark_fraction")]), str(tmp_path))
    scene, figures = figures_of(opt, {OFFSET: 1.0})
    values = search.measure(opt, scene, None, None, figures)[0]
    view = I.view_along(scene, direction(0.0, 0.0), 2.0)
    lum = I.render_view(I.measurement_scene(scene), view)[..., 1]
    h = homogeneity(lum, (I.lamp_of_pixels(scene, view) == 0) & (lum > 0), 2.0)
    assert values == pytest.approx([h.uniformity_min_max, h.uniformity_min_mean, h.cv, h.dark_fraction], rel=1e-5)


@pytest.mark.slow
def test_intensity_at_hv_agrees_with_light_tracing_and_the_grid_margin_reads_it(tmp_path):
    """Two independent estimators of I at H-V: the rendered views (intensity_hv) and light tracing
    (the grid margin's figures) agree within 3 standard errors; the R148 S1 H-V row's margin is
    (I - 60 cd) / 60 cd (S1's minimum at H-V, docs/measures.md)."""
    opt = spec.from_doc(opt_doc(tmp_path, objectives=[{"measure": "intensity_hv"}],
                                constraints=[{"measure": "grid_min_margin", "function": "stop", "min": 0}]),
                        str(tmp_path))
    scene, figures = figures_of(opt, {OFFSET: 0.0})
    values, named, _ = search.measure(opt, scene, None, None, figures)
    traced, variance = figures.grid[0][(0.0, 0.0)]
    rendered_err = figures.axis[0][1]
    assert abs(values[0] - traced) < 3 * np.hypot(rendered_err, np.sqrt(variance)), (values[0], traced)
    rows = P.grid_rows(search.Trial(scene, None, None, figures), opt.constraints[0].prepared)
    hv = next(r for r in rows if r.point == "H-V" and r.kind == "min")
    assert hv.required == 60.0 and hv.margin == pytest.approx((traced - 60.0) / 60.0)
    assert named["grid_min_margin"] == min(r.margin for r in rows)
    # the same figures from light tracing by its own entry point, same seed and photons
    again = traced_intensity(scene, 0.0, 0.0, [0], photons=P.DEFAULT_PHOTONS, cone_deg=P.CONE_DEG, seed=0)
    assert again.cd == pytest.approx(traced, rel=0.25)


@pytest.mark.slow
def test_total_flux_is_the_integral_of_the_rendered_intensities(tmp_path):
    """The light-traced flux leaving the stop lamp against ∫ I dΩ over the front hemisphere from an
    independent estimator, the rendered intensities on a (C, γ) grid (30° by 5°, trapezoids in γ):
    within 5 % (the grid's quadrature; measured 51.6 ± 0.18 lm against 49.6 lm), and below the
    bulb's 440 lm."""
    from core_tracer.measures.export import BeamGrid, lamp_flux, measure_distribution

    opt = spec.from_doc(opt_doc(tmp_path, objectives=[{"measure": "total_flux"}]), str(tmp_path))
    scene, figures = figures_of(opt, {OFFSET: 0.0})
    traced = search.measure(opt, scene, None, None, figures)[0][0]
    stderr = np.sqrt(figures.flux[0][1])
    beam = measure_distribution(scene, grid=BeamGrid(30.0, 5.0, 5.0), photons=0, pixel_mm=2.0, replicates=1)
    gamma = np.radians(beam.gamma_deg)
    integral = 2 * np.pi * np.trapz(beam.cd.mean(axis=0) * np.sin(gamma), gamma)
    assert traced == pytest.approx(integral, rel=0.05), (traced, stderr, integral)
    assert stderr < 0.01 * traced and traced < lamp_flux(scene)


def test_colour_distance_is_signed_inside_and_outside():
    square = ((0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0))
    assert P.signed_distance((0.5, 0.4), square) == pytest.approx(0.4)
    assert P.signed_distance((1.3, 0.5), square) == pytest.approx(-0.3)
    assert P.signed_distance((1.0, 0.5), square) == pytest.approx(0.0)


# ---------------------------------------------------------------------------------------------
# The search


def dense_sweep(opt, lo: float, hi: float, count: int) -> tuple[float, float]:
    scores, sweep = [], np.linspace(lo, hi, count)
    for y in sweep:
        scene, figures = figures_of(opt, {OFFSET: float(y)})
        scores.append(search.measure(opt, scene, None, None, figures)[0][0])
    return min(scores), float(sweep[int(np.argmin(scores))])


@pytest.mark.slow
def test_the_search_reaches_a_dense_sweeps_most_even_lens_with_a_fifth_of_its_renders(tmp_path):
    """The bulb's position along the axis that makes the photometric stop lamp's lit lens most even
    (lowest CV of its luminance from H-V, 2 mm pixels): a 50-value sweep over [-2, 4] mm finds it
    (0.1942 at 1.31 mm; the start, 0 mm, is 0.2229); TPE with 10 trials (a fifth), seed 0, comes
    within 2 %. Seeds 0-7 of the same search: TPE 6 of 8 within 2 %, CMA-ES 7, random 7 (the
    landscape has shelves at 0.1996 and 0.211 just outside): a fixed seed, not a guarantee."""
    opt = spec.from_doc(opt_doc(tmp_path), str(tmp_path))
    sweep_best, where = dense_sweep(opt, -2.0, 4.0, 50)
    outcome = search.run(opt, None, CellCache(tmp_path / "cache"))
    found = storage.best(opt, outcome.study)[0]
    assert outcome.rendered == 10 == 50 // 5
    assert found.values[0] <= 1.02 * sweep_best, (found.values[0], sweep_best, found.params)
    print(f"sweep best {sweep_best:.4f} at {where:.3f} mm; search {found.values[0]:.4f} at "
          f"{found.params[OFFSET]:.3f} mm")
    # A second run of the same file finds every trial's figures in the cache: nothing rendered.
    again = search.run(spec.Optimisation(**{**opt.__dict__, "name": "again"}), None, CellCache(tmp_path / "cache"))
    assert again.rendered == 0 and again.from_cache == 10


@pytest.mark.slow
def test_cmaes_runs_and_improves_on_the_start(tmp_path):
    opt = spec.from_doc(opt_doc(tmp_path, sampler="cmaes", seed=1, trials=8,
                                parameters=[{"parameter": OFFSET, "range": [-2.0, 4.0]},
                                            {"parameter": "cuts.height", "range": [0.5, 2.0]}]), str(tmp_path))
    study = storage.open_study(opt)
    assert isinstance(study.sampler, optuna.samplers.CmaEsSampler)
    outcome = search.run(opt, None, None)
    done = storage.finished_trials(outcome.study)
    start = next(t for t in done if t.number == 0)
    assert start.params == {OFFSET: 0.0, "cuts.height": 1.5}  # the design as given
    best = storage.best(opt, outcome.study)[0]
    assert len(done) == 8 and best.values[0] < 0.97 * start.values[0], (best.values, start.values)


@pytest.mark.slow
def test_a_grid_margin_no_design_can_meet_is_said_after_the_search(tmp_path):
    """A tail filament (35 lm, 11 cd at H-V) held to the stop lamp's R148 S1 grid (60 cd at H-V):
    no cut height makes up the flux; said in one line with the closest trial, and in trials.json."""
    base = read_json(str(TAIL))
    base["lamps"][0]["function"] = "stop"
    (tmp_path / "tail-as-stop.json").write_text(json.dumps(base))
    path = tmp_path / "opt.json"
    path.write_text(json.dumps(opt_doc(tmp_path, base="tail-as-stop.json", trials=3,
                                       parameters=[{"parameter": "cuts.height", "range": [0.5, 2.0]}],
                                       constraints=[{"measure": "grid_min_margin", "function": "stop", "min": 0.0,
                                                     "photons": 5000}])))
    proc = run_cli("optimise", path, "--workers", "0", "-o", tmp_path / "out", "--no-cache")
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert proc.stderr.count("\n") == 1 and proc.stderr.startswith("error: no trial met every constraint; the "
                                                                   "closest is trial "), proc.stderr
    assert "grid_min_margin -0.8" in proc.stderr  # 11 cd of 60: a margin of about -0.82
    trials = json.loads((tmp_path / "out" / "trials.json").read_text())["trials"]
    assert len(trials) == 3 and not any(t["feasible"] for t in trials)
    assert all(t["measures"]["grid_min_margin"] < -0.5 for t in trials)


@pytest.mark.slow
def test_the_sheet_shows_a_red_stop_lamp_red(tmp_path):
    """The trials' images are XYZ in cd/m²: the sheet shows them through the base's camera EV100
    (images.display.shown), not as if X, Y, Z were R, G, B (which turned the red stop
    lamp orange: G/R about 0.7 on its lit lens)."""
    import OpenImageIO as oiio

    path = tmp_path / "opt.json"
    path.write_text(json.dumps(opt_doc(tmp_path, trials=2, size=[48, 48])))
    proc = run_cli("optimise", path, "--workers", "0", "-o", tmp_path / "out", "--no-cache")
    assert proc.returncode == 0, proc.stderr
    sheet = oiio.ImageBuf(str(tmp_path / "out" / "sheet.png")).get_pixels(oiio.FLOAT)[..., :3]
    lit = sheet[..., 0] > 0.5  # the lit lens (the background and the text are grey)
    lit &= np.abs(sheet[..., 0] - sheet[..., 1]) > 0.1
    assert lit.sum() > 50
    assert float(np.median(sheet[..., 1][lit] / sheet[..., 0][lit])) < 0.5


@pytest.mark.slow
def test_designs_light_tracing_cannot_follow_are_refused_trials_not_a_crash(tmp_path):
    """A cylindrical lens among the values: light tracing follows flat lenses only, so those trials
    are refused with the reason (and counted); the flat ones are measured."""
    base = read_json(str(STOP))
    base["body"]["depth"] = 120.0  # room for the curved lens's reflector
    base["lamps"][0]["lens"]["wrap_radius"] = 400.0
    (tmp_path / "base.json").write_text(json.dumps(base))
    opt = spec.from_doc(opt_doc(tmp_path, trials=4, base="base.json", parameters=[
        {"parameter": "lens.shape", "values": ["flat", "cylindrical"]}],
        objectives=[{"measure": "grid_min_margin", "function": "stop", "photons": 2000}]), str(tmp_path))
    outcome = search.run(opt, None, None)
    trials = outcome.study.get_trials(deepcopy=False)
    refused = [t for t in trials if t.user_attrs.get("refused")]
    measured = storage.finished_trials(outcome.study)
    assert refused and measured and len(refused) + len(measured) == 4 and outcome.refused == len(refused)
    assert all(t.user_attrs["design"]["lens.shape"] == "cylindrical" for t in refused)
    assert all("flat-lensed" in t.user_attrs["refused"] for t in refused), [t.user_attrs["refused"] for t in refused]
    assert all(t.user_attrs["design"]["lens.shape"] == "flat" for t in measured)


# ---------------------------------------------------------------------------------------------
# Memory on the workers


@pytest.mark.slow
def test_workers_too_small_for_a_trial_are_refused_in_one_line_before_anything_runs(tmp_path):
    opt = spec.from_doc(opt_doc(tmp_path, trials=2), str(tmp_path))
    need = search.trial_bytes(opt)
    with engine.connect(workers=1, memory_limit=200 * 2**20) as client:
        with pytest.raises(SceneError) as e:
            search.run(opt, client, None)
        assert client.scheduler_info()["workers"]  # the worker is there, and was sent nothing
        address = next(iter(client.scheduler_info()["workers"]))
    message = e.value.message
    assert e.value.path == "--scheduler" and "\n" not in message
    assert f"worker {address} has a memory limit of 200 MB" in message
    assert f"needs about {engine.megabytes(need + engine.DASK_BYTES)}" in message and "allowed" in message
    assert not storage.finished_trials(storage.open_study(opt))


@pytest.mark.slow
def test_trials_go_only_to_the_workers_whose_memory_holds_them(tmp_path):
    """A local cluster of one worker too small (200 MB) and one started beside it with room (2 GiB),
    as `dask worker --memory-limit` starts a studio's node: every trial runs on the large one."""
    opt = spec.from_doc(opt_doc(tmp_path, trials=3), str(tmp_path))
    with small_and_large_worker() as (client, small, large):
        with get_task_stream(client) as stream:
            outcome = search.run(opt, client, None, parallel=2)
        ran_on = {t["worker"] for t in stream.data if str(t["key"]).startswith("lamp-trial-")}
    assert outcome.workers == [large] and small not in outcome.workers
    assert ran_on == {large}, ran_on
    assert len(storage.finished_trials(outcome.study)) == 3 and outcome.rendered == 3


def test_a_measured_filter_beside_the_base_reaches_every_trial(tmp_path):
    """The base names its lens filter by a measured curve beside it (issue 32, item 4): the optimisation
    file elsewhere finds it beside the base, each trial's cell carries it (a Dask worker need not see
    the folder), and a missing curve is refused in one line before any trial."""
    import json

    from core_tracer.photometry import materials

    folder = tmp_path / "design"
    folder.mkdir()
    curve = materials.FILTERS["red"].spectrum()
    doc = json.loads(STOP.read_text())
    doc["lamps"][0]["lens"].update(filter="file", filter_file="red.csv")
    (folder / "stop.json").write_text(json.dumps(doc))
    with pytest.raises(SceneError) as err:
        spec.from_doc(opt_doc(tmp_path, base="design/stop.json"), str(tmp_path))
    assert "base.lamps[0].lens.filter_file" in str(err.value) and "missing" in str(err.value)
    (folder / "red.csv").write_text("nm,t\n" + "".join(f"{a:g},{b:.8f}\n" for a, b in
                                                       zip(curve.wavelengths_nm, curve.values, strict=True)))
    opt = spec.from_doc(opt_doc(tmp_path, base="design/stop.json"), str(tmp_path))
    scene = opt.scene_of({OFFSET: 0.0})
    assert scene["lamps"][0]["lens"]["filter_file"] == "red.csv"  # the trial's design keeps the name
    cell = make_cell(opt.traced(scene), *opt.size, Inputs())
    assert len(cell.curves) == 1
    named = opt_doc(tmp_path)  # the preset itself: the same filter by name
    _, _, by_file = T.run_trial(cell, None, None, False, opt.request)
    _, by_name = figures_of(spec.from_doc(named, str(tmp_path)), {OFFSET: 0.0})
    lit = by_name.front_owner == 0
    assert lit.sum() > 50
    assert by_file.front_luminance[lit].mean() == pytest.approx(by_name.front_luminance[lit].mean(), rel=2e-3)
