"""A light-states file is checked before it is trusted (issue 33 item 1): sizes from the zip's
directory and each array's header before anything is inflated, the header's scene validated again,
its states and stats those of that scene, every array float32 of the scene's size and finite."""

from __future__ import annotations

import io
import json
import resource
import time

import helpers
import hostile_files as H
import numpy as np
import pytest

from core_tracer.measures import states as S
from core_tracer.scene.reading import SceneError
from core_tracer.scene.validate import parse_scene


@pytest.fixture(scope="module")
def good() -> bytes:
    doc = helpers.baseline_doc()
    doc["image"].update(width=24, height=16, samples=1)
    return S.to_bytes(S.render_states(parse_scene(doc)))


def _refused(data: bytes, *words: str) -> str:
    with pytest.raises(SceneError) as e:
        S.from_bytes(data, "f.npz")
    for word in words:
        assert word in e.value.message, e.value.message
    return e.value.message


def test_a_good_file_reads_back(good):
    light = S.from_bytes(good)
    assert light.surroundings.shape == (16, 24, 3) and light.surroundings.flags.writeable


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_pass_holding_nan_or_inf_is_refused(good, value):
    parts = H.members(good)
    array = np.lib.format.read_array(io.BytesIO(parts["pass_0.npy"]))
    array[3, 4, 1] = value
    _refused(H.npz_of({**parts, "pass_0.npy": H.npy_bytes(array)}), "not finite")


def test_an_array_of_another_size_or_type_is_refused(good):
    parts = H.members(good)
    _refused(H.npz_of({**parts, "pass_0.npy": H.npy_bytes(np.zeros((17, 24, 3), np.float32))}), "shape 17x24x3",
             "allowed 16x24x3")
    _refused(H.npz_of({**parts, "surroundings.npy": H.npy_bytes(np.zeros((16, 24, 3)))}), "float64")
    _refused(H.npz_of({**parts, "surroundings.npy": H.npy_bytes(np.array([None], object))}), "object")


def test_a_scene_that_does_not_validate_is_refused_naming_its_field(good):
    parts = H.members(good)
    header = json.loads(np.lib.format.read_array(io.BytesIO(parts["header.npy"])).tobytes())
    header["scene"]["image"]["width"] = 1e308
    _refused(H.npz_of({**parts, "header.npy": H.npy_bytes(np.frombuffer(json.dumps(header).encode(), np.uint8))}),
             "image.width")


def test_states_and_stats_must_be_those_of_the_scene(good):
    parts = H.members(good)
    header = json.loads(np.lib.format.read_array(io.BytesIO(parts["header.npy"])).tobytes())

    def with_header(h: dict) -> bytes:
        return H.npz_of({**parts, "header.npy": H.npy_bytes(np.frombuffer(json.dumps(h).encode(), np.uint8))})

    _refused(with_header({**header, "states": header["states"][:1]}), "states do not match")
    _refused(with_header({**header, "states": [{**s, "rendered": 0.0} for s in header["states"]]}), "rendered at")
    _refused(with_header({**header, "stats": {"light_model": "photometric", "bands": 10**9}}), "light model")


def test_a_member_claiming_1_7_gb_is_refused_from_its_sizes_in_under_a_second_without_the_memory(good):
    parts = H.members(good)
    bomb = H.zeros_bomb("pass_0.npy", H.npy_header((12000, 11806, 3)), 12000 * 11806 * 12,
                        {k: v for k, v in parts.items() if k != "pass_0.npy"})
    assert len(bomb) < 3_000_000
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.perf_counter()
    _refused(bomb, "shape 12000x11806x3", "allowed 16x24x3")
    assert time.perf_counter() - start < 1.0
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 100_000  # kB


def test_a_member_whose_data_inflates_past_what_its_directory_says_stops_there(good):
    parts = H.members(good)
    header = H.npy_header((16, 24, 3))
    bomb = H.zeros_bomb("pass_0.npy", header, 10**9, {k: v for k, v in parts.items() if k != "pass_0.npy"},
                        claimed=len(header) + 16 * 24 * 12)
    start = time.perf_counter()
    _refused(bomb, "cannot be inflated")
    assert time.perf_counter() - start < 1.0


@pytest.mark.slow
def test_relight_refuses_a_bomb_in_one_line_fast(good, tmp_path):
    parts = H.members(good)
    path = tmp_path / "bomb.npz"
    path.write_bytes(H.zeros_bomb("surroundings.npy", H.npy_header((12000, 11806, 3)), 12000 * 11806 * 12,
                                  {k: v for k, v in parts.items() if k != "surroundings.npy"}))
    start = time.perf_counter()
    helpers.assert_bad_input(helpers.run_cli("relight", path, "-o", tmp_path / "x.png"), "bomb.npz", "12000x11806x3")
    assert time.perf_counter() - start < 30  # the interpreter's start included, on a loaded machine
    assert not (tmp_path / "x.png").exists()


@pytest.mark.slow
def test_relight_never_writes_a_non_finite_image(good, tmp_path):
    """Finite passes whose weighted sum overflows float32 are refused at the writer (exit 2, nothing written)."""
    parts = H.members(good)
    array = np.full((16, 24, 3), 3e38, np.float32)
    path = tmp_path / "huge.npz"
    path.write_bytes(H.npz_of({**parts, "surroundings.npy": H.npy_bytes(array)}))
    for out in ("x.exr", "x.png"):
        done = helpers.run_cli("relight", path, "-o", tmp_path / out, "--level", "surroundings=100")
        helpers.assert_bad_input(done, "not finite")
        assert not (tmp_path / out).exists()


def test_a_state_rendered_at_a_number_of_400_digits_is_refused(good):
    """Found by the campaign: math.isclose overflowed on it."""
    parts = H.members(good)
    header = json.loads(np.lib.format.read_array(io.BytesIO(parts["header.npy"])).tobytes())
    header["states"][1]["rendered"] = 10**400
    text = json.dumps(header).encode()
    _refused(H.npz_of({**parts, "header.npy": H.npy_bytes(np.frombuffer(text, np.uint8))}), "rendered at")


def test_a_photometric_file_keeps_its_bands_and_an_older_one_reads_as_uniform_bands():
    """The bands the scene chose (narrow where an LED's line is) travel with the file, so ``relight``
    writes its images on them; a file written before the scene chose its bands has none and read its
    K bands as uniform; edges that are not K + 1 increasing wavelengths are refused."""
    from core_tracer.photometry.bands import Bands

    doc = json.loads((helpers.PRESETS / "led-stop-lamp.json").read_text())
    doc["image"].update(width=24, height=16, samples=1)
    data = S.to_bytes(S.render_states(parse_scene(doc)))
    stats = S.from_bytes(data).stats
    edges = stats["band_edges_nm"]
    assert len(edges) == stats["bands"] + 1 and edges != Bands.uniform(stats["bands"]).edges_nm.tolist()

    parts = H.members(data)
    header = json.loads(np.lib.format.read_array(io.BytesIO(parts["header.npy"])).tobytes())

    def with_stats(given: dict) -> bytes:
        h = {**header, "stats": given}
        return H.npz_of({**parts, "header.npy": H.npy_bytes(np.frombuffer(json.dumps(h).encode(), np.uint8))})

    older = {k: v for k, v in header["stats"].items() if k != "band_edges_nm"}
    assert S.from_bytes(with_stats(older)).stats["band_edges_nm"] == Bands.uniform(stats["bands"]).edges_nm.tolist()
    _refused(with_stats({**header["stats"], "band_edges_nm": edges[::-1]}), "band edges")
    _refused(with_stats({**header["stats"], "band_edges_nm": edges[:-1]}), "band edges")
