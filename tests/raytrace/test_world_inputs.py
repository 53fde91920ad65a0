"""Environment images as hostile inputs (issue 21): checked by their header before any pixel is
read, confined beside the scene file, finite in the output, refused in one line; and the world made
once, kept in a mapped cache file that the band pool's workers share (issue 20, item 7)."""

from __future__ import annotations

import json
import os
import shutil

import numpy as np
import pytest
from helpers import assert_bad_input, baseline_doc, run_cli, scene_with, write_exr

from core_tracer import render_passes
from core_tracer.images.imageio import read_image
from core_tracer.raytrace import environment, world_cache, world_image
from core_tracer.scene.reading import SceneError

HDR_HEAD = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"


@pytest.fixture(autouse=True)
def own_cache(tmp_path, monkeypatch):
    """Every test its own world cache folder (the CLI's subprocesses inherit the variable)."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(world_cache.ENV_FOLDER, str(folder))
    world_cache.clear_memory()
    yield folder
    world_cache.clear_memory()


def _sky(h: int = 16, w: int = 32) -> np.ndarray:
    rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    return np.stack([1.0 + cols / w, 1.0 + rows / h, np.full((h, w), 0.5)], axis=-1).astype(np.float32)


def _preset(folder, environment_section: dict, name: str = "scene.json", size: int = 8) -> str:
    doc = baseline_doc()
    doc["image"] = {"width": size, "height": size}
    doc["environment"] = {"strength": 1.0, **environment_section}
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(json.dumps(doc))
    return str(path)


# -- images that declare more than they hold --------------------------------------------------------

BOMBS = {
    "wide.hdr": (HDR_HEAD + b"-Y 15000 +X 30000\n", "declares 30000x15000 px"),
    "huge.hdr": (HDR_HEAD + b"-Y 100000 +X 100000\n", "declares 100000x100000 px"),
    "negative.hdr": (HDR_HEAD + b"-Y -5 +X 100\n", "its header declares 100x-5 px"),
    "truncated.hdr": (HDR_HEAD + b"-Y 64 +X 128\n" + b"\x02\x02\x00\x80" * 10, "cannot be read as an image"),
}


@pytest.fixture(params=sorted(BOMBS))
def bomb(request, tmp_path) -> tuple[str, str]:
    name = request.param
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / name).write_bytes(BOMBS[name][0])
    return name, BOMBS[name][1]


@pytest.mark.slow
def test_a_header_bomb_is_refused_by_render_in_one_line(tmp_path, bomb):
    name, said = bomb
    scene = _preset(tmp_path / "lib", {"world": "file", "file": name})
    assert_bad_input(run_cli("render", scene, "-o", tmp_path / "out.exr", timeout=120), "environment.file", name,
                     said)
    assert not (tmp_path / "out.exr").exists()


@pytest.mark.slow
def test_a_header_bomb_is_refused_before_the_band_pool_starts(tmp_path, bomb):
    name, said = bomb
    scene = _preset(tmp_path / "lib", {"world": "file", "file": name})
    # 1024 x 1024 at 2 samples: heavy enough for the band pool's worker processes
    proc = run_cli("render", scene, "-o", tmp_path / "out.exr", "--width", 1024, "--height", 1024, "--samples", 2,
                   timeout=120)
    assert_bad_input(proc, "environment.file", name, said)


@pytest.mark.slow
def test_a_header_bomb_is_refused_by_a_study_in_one_line(tmp_path, bomb):
    name, said = bomb
    scene = _preset(tmp_path / "lib", {"world": "file", "file": name})
    proc = run_cli("study", scene, "--vary", "lens.ior=1.45:1.55:2", "--size", "16x16", "-o", tmp_path / "s.png",
                   timeout=120)
    assert_bad_input(proc, "environment.file", name, said)


def test_a_header_bomb_is_refused_in_process_without_reading_pixels(tmp_path, bomb):
    name, said = bomb
    scene = scene_with(**{"environment": {"world": "file", "file": str(tmp_path / "lib" / name)}})
    with pytest.raises(SceneError, match=said):
        render_passes(scene, 4, 4)


def test_a_large_image_is_area_averaged_to_the_limit_while_it_is_read(tmp_path, monkeypatch):
    sky = _sky(32, 64)
    path = write_exr(tmp_path / "big.exr", sky)
    monkeypatch.setattr(world_image, "MAX_PIXELS", 16 * 32)  # a 64 x 32 image is 4 times that
    assert world_image.factor_for(64, 32) == 2
    pixels = environment.read_image(path)
    assert pixels.shape == (16, 32, 3)
    np.testing.assert_allclose(pixels, sky.reshape(16, 2, 32, 2, 3).mean(axis=(1, 3)), rtol=1e-6)


def test_the_header_estimate_enters_the_render_budget(tmp_path):
    path = write_exr(tmp_path / "sky.exr", _sky())
    scene = scene_with(**{"environment": {"world": "file", "file": path}})
    assert environment.world_bytes(scene) == world_image.peak_bytes(32, 16, 3) > 0
    assert environment.world_bytes(scene_with()) == 0


# -- environment.file confined beside the scene file ------------------------------------------------


@pytest.fixture
def library(tmp_path) -> dict:
    """lib/ with a sky beside its presets, and a sky outside it."""
    lib, outside = tmp_path / "lib", tmp_path / "outside"
    lib.mkdir()
    outside.mkdir()
    write_exr(lib / "sky.exr", _sky())
    write_exr(outside / "far.exr", _sky())
    os.symlink(outside / "far.exr", lib / "link.exr")
    return {"lib": lib, "outside": outside, "far": str(outside / "far.exr")}


@pytest.mark.slow
@pytest.mark.parametrize("form", ["absolute", "dotdot", "symlink", "folder"])
def test_an_environment_path_out_of_the_scene_folder_is_refused(tmp_path, library, form):
    file = {"absolute": library["far"], "dotdot": "../outside/far.exr", "symlink": "link.exr",
            "folder": "sub/sky.exr"}[form]
    said = "leads outside" if form == "symlink" else "is not allowed"
    scene = _preset(library["lib"], {"world": "file", "file": file}, name=f"{form}.json")
    assert_bad_input(run_cli("render", scene, "-o", tmp_path / "out.exr"), "environment.file", said)
    assert_bad_input(run_cli("validate", scene), "environment.file", said)
    proc = run_cli("presets", "validate", library["lib"])
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert any(f"{form}.json" in line and "environment.file" in line and said in line
               for line in proc.stderr.splitlines()), proc.stderr
    study = run_cli("study", scene, "--vary", "lens.ior=1.45:1.55:2", "--size", "16x16", "-o", tmp_path / "s.png")
    assert_bad_input(study, "environment.file", said)


@pytest.mark.slow
def test_an_image_beside_the_scene_renders_from_another_working_directory(tmp_path, library):
    scene = _preset(library["lib"], {"world": "file", "file": "sky.exr"})
    # run_cli works in the repository's folder, not the scene's
    proc = run_cli("render", scene, "-o", tmp_path / "out.exr")
    assert proc.returncode == 0, proc.stderr
    image, stored = read_image(tmp_path / "out.exr")
    assert stored["environment"]["file"] == "sky.exr"  # the file records the name, not a path of this machine
    sheet = run_cli("study", scene, "--vary", "lens.ior=1.45:1.55:2", "--size", "16x16", "--workers", "1",
                    "-o", tmp_path / "s.png")
    assert sheet.returncode == 0, sheet.stderr
    assert run_cli("presets", "validate", library["lib"]).returncode == 0
    thumbnails = run_cli("presets", "thumbnails", library["lib"])
    assert thumbnails.returncode == 0, thumbnails.stderr
    assert list((library["lib"] / "thumbnails").glob("scene*.png"))


@pytest.mark.slow
def test_a_users_own_image_elsewhere_is_given_on_the_command_line(tmp_path, library):
    scene = _preset(library["lib"], {"world": "none"})
    proc = run_cli("render", scene, "-o", tmp_path / "out.exr", "--environment", library["far"])
    assert proc.returncode == 0, proc.stderr
    image, stored = read_image(tmp_path / "out.exr")
    assert stored["environment"] == {**stored["environment"], "world": "file", "file": "far.exr"}
    assert run_cli("render", scene, "-o", tmp_path / "plain.exr").returncode == 0
    assert not np.array_equal(image, read_image(tmp_path / "plain.exr")[0])  # the sky shows
    assert_bad_input(run_cli("render", scene, "-o", tmp_path / "x.exr", "--environment", tmp_path / "none.exr"),
                     "--environment", "does not exist")


# -- values: finite out, one line for every refusal -------------------------------------------------


@pytest.mark.slow
def test_an_absurdly_bright_sky_gives_a_finite_image_without_warnings(tmp_path):
    # Before: inf in 60 of the 64 pixels, exit 0, and numpy's overflow warning on stderr.
    sky = np.full((16, 32, 3), 3e38, np.float32)
    sky[4, 6] = np.nan
    sky[5, 7] = np.inf
    lib = tmp_path / "lib"
    lib.mkdir()
    write_exr(lib / "sun.exr", sky)
    scene = _preset(lib, {"world": "file", "file": "sun.exr", "strength": 10.0}, size=8)
    proc = run_cli("render", scene, "-o", tmp_path / "out.exr", "--samples", 4)
    assert proc.returncode == 0, proc.stderr
    assert "Warning" not in proc.stderr and proc.stderr == ""  # no numpy warning either
    image, _ = read_image(tmp_path / "out.exr")
    assert np.isfinite(image).all()
    pixels = environment.read_image(str(lib / "sun.exr"))
    assert pixels[3, 5, 0] == world_image.MAX_RADIANCE and pixels[4, 6, 0] == 0.0 and pixels[5, 7, 0] == 0.0
    assert image.max() <= 10.0 * world_image.MAX_RADIANCE


@pytest.mark.slow
@pytest.mark.parametrize("content", [b"not an image at all", b"\x76\x2f\x31\x01" + bytes(60)])
def test_a_broken_image_is_one_line_without_library_messages(tmp_path, content):
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "broken.exr").write_bytes(content)
    scene = _preset(lib, {"world": "file", "file": "broken.exr"})
    assert_bad_input(run_cli("render", scene, "-o", tmp_path / "out.exr"), "environment.file", "broken.exr",
                     "cannot be read as an image")


# -- the world made once, cached, shared --------------------------------------------------------------


def test_the_world_is_cached_by_content_and_a_damaged_cache_file_is_made_again(tmp_path, own_cache):
    path = write_exr(tmp_path / "sky.exr", _sky())
    scene = scene_with(**{"image": {"width": 8, "height": 8},
                          "environment": {"world": "file", "file": path, "rotation_deg": 30.0}})
    first = render_passes(scene).image
    files = sorted(os.listdir(own_cache / "worlds"))
    assert sorted(f.rsplit(".", 1)[1] for f in files) == ["image", "turn"]  # the pixels, what the turn makes of them
    world_cache.clear_memory()
    copy = tmp_path / "copy.exr"
    shutil.copy(path, copy)  # the same bytes elsewhere: the same files
    again = render_passes({**scene, "environment": {**scene["environment"], "file": str(copy)}}).image
    np.testing.assert_array_equal(first, again)
    assert sorted(os.listdir(own_cache / "worlds")) == files
    turned = {**scene, "environment": {**scene["environment"], "rotation_deg": 50.0}}
    render_passes(turned)  # another turn: its own .turn file, the same .image
    assert len(os.listdir(own_cache / "worlds")) == 3
    for name in files:
        cached = own_cache / "worlds" / name
        data = bytearray(cached.read_bytes())
        data[len(data) * 3 // 4] ^= 0xFF  # one damaged byte: the CRC notices, the file is made again
        cached.write_bytes(bytes(data))
        world_cache.clear_memory()
        np.testing.assert_array_equal(render_passes(scene).image, first)
        cached.write_bytes(b"LAMPWLD1 garbage")
        world_cache.clear_memory()
        np.testing.assert_array_equal(render_passes(scene).image, first)
    assert not [f for f in os.listdir(own_cache / "worlds") if f.startswith(".tmp-")]


def test_the_cache_folder_stays_within_its_bound(tmp_path, own_cache, monkeypatch):
    monkeypatch.setattr(world_cache, "MAX_CACHE_BYTES", 1)  # keep only the newest
    for i in range(3):
        path = write_exr(tmp_path / f"sky{i}.exr", _sky() + i)
        environment.from_scene(scene_with(**{"environment": {"world": "file", "file": path}}))
    assert len(os.listdir(own_cache / "worlds")) == 2  # the newest image and its turn


def test_an_unsafe_cache_folder_is_not_used(tmp_path, own_cache):
    os.makedirs(own_cache / "worlds")
    os.chmod(own_cache / "worlds", 0o777)
    assert world_cache.cache_folder() is None
    path = write_exr(tmp_path / "sky.exr", _sky())
    env = environment.from_scene(scene_with(**{"environment": {"world": "file", "file": path}}))
    assert env.world.file is None and env.pixels.shape == (16, 32, 3)  # made in memory


@pytest.mark.slow
def test_the_band_workers_map_the_parents_world_file(tmp_path, own_cache, monkeypatch):
    from core_tracer.raytrace.band_pool import BandPool
    from core_tracer.raytrace.engine import sampling

    monkeypatch.setattr(sampling, "TILE_RAYS", 64 * 8)  # bands of 8 rows: both workers take some

    path = write_exr(tmp_path / "sky.exr", _sky())
    scene = scene_with(**{"image": {"width": 64, "height": 64},
                          "environment": {"world": "file", "file": path}})
    pool = BandPool(2)
    try:
        assert pool.ready(30.0)
        result = render_passes(scene, pool=pool, threads=2)
        assert result.stats["worker_processes"] >= 1
        world_file = environment.from_scene(scene).world.file
        assert world_file is not None
        mapped = [pid for pid in pool.process_ids() if world_file in open(f"/proc/{pid}/maps").read()]
        assert mapped, "no band worker maps the world file"
        np.testing.assert_array_equal(result.image, render_passes(scene).image)
    finally:
        pool.close()
