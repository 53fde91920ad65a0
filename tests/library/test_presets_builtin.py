"""The built-in presets: the paper's studies (Figs. 12-19), a lamp-off view and a four-lamp rear combination."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from helpers import PRESETS

from core_tracer import render
from core_tracer.images import imageio
from core_tracer.library import presets as P
from core_tracer.library import shipping
from core_tracer.scene.derived import lamp_geometry, lens_absorption
from core_tracer.scene.messages import leaves
from core_tracer.scene.reading import read_json
from core_tracer.scene.validate import parse_scene

FILES = sorted(PRESETS.glob("*.json"))
AUTHOR = "Lamp Styling (after Nishio et al. 1990)"

# Each study changes exactly these fields of the baseline (leaf paths, lamp 0).
STUDIES = {
    "paper-body-color": {"body.color"},
    "paper-lens-color": {"lamps[0].lens.absorption", "lamps[0].lens.transmitted_color",
                         "lamps[0].lens.reference_thickness", "lamps[0].lens.diffuse_color"},
    "paper-cut-size": {"lamps[0].cuts.pitch", "lamps[0].cuts.height"},
    "paper-cut-height": {"lamps[0].cuts.height"},
    "paper-refractive-index": {"lamps[0].lens.ior"},
    "paper-lens-thickness": {"lamps[0].lens.thickness"},
    "paper-bulb-brightness": {"lamps[0].bulb.intensity"},
    "paper-bulb-position": {"lamps[0].bulb.offset"},
    "paper-lamp-off": {"lamps[0].bulb.on"},
}
META = {"name", "author", "description", "tags"}


def load(stem: str) -> dict:
    return parse_scene(read_json(PRESETS / f"{stem}.json"))


def test_the_expected_presets_exist():
    stems = {f.stem for f in FILES}
    assert {"paper-baseline", "four-lamp-rear-combination", *STUDIES} <= stems
    assert all(f.stem == f.stem.lower() and " " not in f.stem and "_" not in f.stem for f in FILES)


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_every_preset_validates(path):
    scene = parse_scene(read_json(path))
    assert scene.get("light_model", "paper") in scene["tags"]  # "paper" or "photometric", as the browser filters
    assert scene["name"]


@pytest.mark.parametrize("path", [f for f in FILES if f.stem != "paper-baseline"], ids=lambda p: p.stem)
def test_every_preset_is_described(path):
    scene = parse_scene(read_json(path))
    assert scene["author"] == AUTHOR
    assert len(scene["description"]) > 40
    assert len(scene["tags"]) >= 2


@pytest.mark.parametrize("stem", sorted(STUDIES))
def test_each_study_changes_only_its_parameter(stem):
    base = leaves(load("paper-baseline"))
    study = leaves(load(stem))
    changed = {k for k in base.keys() | study.keys() if base.get(k) != study.get(k)} - META
    assert changed == STUDIES[stem]


def test_lens_colour_study_is_amber():
    lens = load("paper-lens-color")["lamps"][0]["lens"]
    assert "transmitted_color" in lens and "absorption" not in lens
    a = lens_absorption(lens)
    assert a[0] < a[1] < a[2]  # red passes best, then green, blue hardly at all


def test_bulb_position_study_moves_the_bulb_off_the_focus():
    lamp = load("paper-bulb-position")["lamps"][0]
    g = lamp_geometry(lamp)
    assert g["bulb_center"][1] - g["focus"] == pytest.approx(6.0)


def test_four_lamp_rear_combination():
    scene = load("four-lamp-rear-combination")
    lamps = scene["lamps"]
    assert len(lamps) == 4
    # all lenses inside the body and apart (parse_scene checks it too; restated here on purpose)
    bx, bz = scene["body"]["center"]
    w, h = scene["body"]["size"]
    for i, lamp in enumerate(lamps):
        (x, z), r = lamp["center"], lamp["lens"]["radius"]
        assert abs(x - bx) + r <= w / 2 and abs(z - bz) + r <= h / 2
        for other in lamps[:i]:
            assert math.dist(lamp["center"], other["center"]) >= r + other["lens"]["radius"]
    tail, stop, turn, reverse = (lens_absorption(lamp["lens"]) for lamp in lamps)
    for red in (tail, stop):
        assert red[0] < 0.1 < red[1] and red[0] < red[2]
    assert turn[0] < turn[1] < turn[2]  # amber
    assert max(reverse) < 0.02  # clear
    assert sum(lamps[1]["bulb"]["intensity"]) > sum(lamps[0]["bulb"]["intensity"])  # stop brighter than tail
    assert all(lamp["bulb"]["on"] for lamp in lamps)


@pytest.mark.slow
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_every_preset_renders(path):
    scene = parse_scene(read_json(path))
    image = render(scene, 48, 48)
    assert image.shape == (48, 48, 3)
    assert np.isfinite(image).all()
    assert (image >= 0).all()
    assert image.max() > 0


@pytest.mark.slow
@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_every_preset_ships_its_thumbnail(path, tmp_path):
    entries, warnings = P.list_presets([P.builtin_library()])
    assert warnings == []
    (entry,) = [e for e in entries if Path(e.file).name == path.name]
    shipped = P.shipped_thumbnail(entry)
    assert shipped is not None, (f"presets/{path.name} is new or changed: presets/{P.SHIPPED_THUMBNAIL_FOLDER}/ has "
                                 f"no {P.thumbnail_name(entry)}; regenerate the thumbnails with "
                                 f"`{P.REGENERATE_COMMAND}` (from the repository root)")
    # the browser shows the shipped file and makes nothing
    cache = tmp_path / "cache"
    assert P.thumbnail_path(entry, cache) == shipped and not cache.exists()
    image, scene = imageio.read_image(shipped)
    assert image.shape == (P.THUMBNAIL_SIZE, P.THUMBNAIL_SIZE, 3)
    assert np.isfinite(image).all() and image.max() > 0
    # it is a render of this very preset, not a renamed file
    assert P.digest(dict(scene, image=entry.scene["image"])) == entry.digest


def test_no_stale_shipped_thumbnails():
    state = shipping.check_shipped_thumbnails(P.builtin_library())
    assert state.stale == (), (f"thumbnails of no current preset: {', '.join(state.stale)}; remove them with "
                               f"`{P.REGENERATE_COMMAND}`")
