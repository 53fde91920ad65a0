"""Small committed reference renders, one for every preset in presets/ (64 x 48 pixels, the preset's
own samples), compared with OpenImageIO's metrics (idiff): a render passes when at most 0.1 % of its
pixels differ from the reference by more than 1e-4 of the reference's peak in a channel.

A failing comparison writes the render and a difference image to tests/raytrace/_failures/. After a
deliberate change to the model, or for a new preset, regenerate the references on purpose:

    .venv/bin/python tests/raytrace/test_reference_images.py --regenerate [case ...]

(every case when none is named; a case is a preset's file name without .json).

The photometric references hold CIE XYZ (Y in cd/m²) under the channel names R, G, B, as
``core_tracer.render`` returns it; their header carries OpenEXR's ``chromaticities`` of CIE XYZ
((1, 0), (0, 1), (0, 0), white (1/3, 1/3)) and ``whiteLuminance`` 1, so Blender, OpenImageIO or
any other reader takes them for XYZ, not Rec.709 (``imageio.XYZ_CHROMATICITIES``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # run as a script (--regenerate): helpers and the project
sys.path.insert(0, str(HERE.parent.parent))

import OpenImageIO as oiio  # noqa: E402
from helpers import PRESETS  # noqa: E402

from core_tracer import load_scene, render  # noqa: E402
from core_tracer.images.imageio import XYZ_CHROMATICITIES, read_image, write_image  # noqa: E402

REFERENCES = HERE / "references"
FAILURES = HERE / "_failures"
SIZE = (64, 48)
# The surroundings presets need Blender's world images (the bpy module's); without them they are skipped.
WORLD_CASES = tuple(f"four-lamp-{time}-{state}" for time in ("day", "evening", "night") for state in ("lit", "unlit"))
CASES = tuple(sorted(path.stem for path in PRESETS.glob("*.json")))  # every preset
FAIL_ABS = 1e-4  # per channel, relative to the image's peak
FAIL_FRACTION = 0.001  # pixels allowed past it (rays grazing a crease between lenslets)


def _render(case: str) -> tuple[np.ndarray, dict]:
    scene = load_scene(PRESETS / f"{case}.json")
    return render(scene, *SIZE), scene


def _buf(image: np.ndarray) -> oiio.ImageBuf:
    h, w = image.shape[:2]
    buf = oiio.ImageBuf(oiio.ImageSpec(w, h, 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(image, dtype=np.float32))
    return buf


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES)
def test_render_matches_reference(case, request):
    if case in WORLD_CASES:
        request.getfixturevalue("world_images")
    reference_file = REFERENCES / f"{case}.exr"
    assert reference_file.exists(), f"missing {reference_file}; run {Path(__file__).name} --regenerate"
    reference, scene_in_header = read_image(reference_file)
    image, scene = _render(case)
    assert scene_in_header == scene, "the preset changed since the reference was made: regenerate on purpose"
    peak = float(reference.max())
    result = oiio.ImageBufAlgo.compare(_buf(image), _buf(reference), FAIL_ABS * peak, FAIL_ABS * peak * 0.1)
    failed_fraction = result.nfail / image[..., 0].size
    if failed_fraction > FAIL_FRACTION:
        FAILURES.mkdir(exist_ok=True)
        write_image(FAILURES / f"{case}.exr", image, scene)
        diff = oiio.ImageBufAlgo.absdiff(_buf(image), _buf(reference))
        diff.write(str(FAILURES / f"{case}-diff.exr"))
    assert failed_fraction <= FAIL_FRACTION, (
        f"{case}: {result.nfail} pixels differ by more than {FAIL_ABS * peak:.3g} "
        f"(mean error {result.meanerror:.3g}, max {result.maxerror:.3g}, PSNR {result.PSNR:.1f} dB); "
        f"see {FAILURES}")


@pytest.mark.parametrize("case", CASES)
def test_a_reference_says_what_its_values_are(case):
    """A photometric reference's R, G, B are CIE XYZ: its header says so (chromaticities of XYZ,
    whiteLuminance 1 cd/m²), so another reader does not take them for Rec.709; a paper one is RGB."""
    spec = oiio.ImageInput.open(str(REFERENCES / f"{case}.exr")).spec()
    chromaticities = spec.getattribute("chromaticities")
    if load_scene(PRESETS / f"{case}.json")["light_model"] == "photometric":
        assert chromaticities == pytest.approx(XYZ_CHROMATICITIES) and spec.getattribute("whiteLuminance") == 1.0
    else:
        assert chromaticities is None


def regenerate(cases: list[str]) -> None:
    REFERENCES.mkdir(exist_ok=True)
    for case in cases or CASES:
        image, scene = _render(case)
        # a photometric render is CIE XYZ (Y in cd/m²) under the channel names R, G, B, which the
        # comparison reads; the header's chromaticities say so to every other reader (Blender too)
        write_image(REFERENCES / f"{case}.exr", image, scene, xyz=scene["light_model"] == "photometric")
        print(f"wrote {REFERENCES / case}.exr  peak {image.max():.4g}")


if __name__ == "__main__":
    if sys.argv[1:2] != ["--regenerate"] or not set(sys.argv[2:]) <= set(CASES):
        print(__doc__)
        raise SystemExit(2)
    regenerate(sys.argv[2:])
