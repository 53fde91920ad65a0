"""Hostile environment images, generated, rendered through the command line (its ``main``, in this
process): Radiance .hdr headers and pixels, OpenEXR files written by OpenImageIO and then damaged,
files whose first bytes are another format's, and ``environment.file`` names that try to leave the
preset's folder (issue 21).

Every answer is either exit 0 with a finite image and nothing on stderr, or exit 2 with exactly one
line on stderr that names ``environment.file`` (or the scene's own field) and the file; never a
traceback, a warning, a library's own message, a read of a file outside the preset's folder, or
more memory than the estimate the render was checked against (the process's peak resident memory,
reset before each input through /proc/self/clear_refs).

The default run takes seconds. ``LAMP_FUZZ_EXAMPLES=N`` multiplies every test's number of examples
by N for a long run, e.g. ``LAMP_FUZZ_EXAMPLES=50 pytest tests/raytrace/test_fuzz_world_images.py``.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import struct
import sys
import tempfile
import warnings

import numpy as np
import pytest
from helpers import baseline_doc, fuzz, status_bytes
from hypothesis import currently_in_test_context, event, given
from hypothesis import strategies as st

from core_tracer import budget
from core_tracer.cli.main import main
from core_tracer.images import imageio
from core_tracer.raytrace import world_cache, world_image
from core_tracer.scene.reading import SceneError
from core_tracer.scene.safe_text import printable

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")

MIB = 2**20


# -- what every answer must be -------------------------------------------------------------------

_opened_paths: list[str] | None = None  # while a render runs: every file Python opens or stats


def _audit(event: str, args: tuple) -> None:
    if _opened_paths is not None and event in ("open", "os.listdir", "os.scandir") and args:
        path = args[0]
        if isinstance(path, (str, bytes)):
            _opened_paths.append(os.fsdecode(path))


sys.addaudithook(_audit)  # for the life of the process; it records only while a render runs


def _declared_bytes(path: str) -> int:
    """What the render's check counted for the world of the image at ``path`` (0: none, refused)."""
    try:
        return world_image.peak_bytes(*world_image.header(path))
    except (SceneError, OSError):
        return 0


@pytest.fixture
def space(tmp_path, monkeypatch):
    """A world cache of this test's own; the folder every input's library is made in."""
    monkeypatch.setenv(world_cache.ENV_FOLDER, str(tmp_path / "cache"))
    world_cache.clear_memory()
    yield tmp_path
    world_cache.clear_memory()


def run_main(capfd, argv: list[str]) -> tuple[int, str, int, list[str]]:
    """(exit status, stderr, growth of the peak resident memory, files Python opened) of the command
    line ``argv`` in this process; any exception or warning fails the test."""
    global _opened_paths
    capfd.readouterr()
    rss = status_bytes("VmRSS")
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")  # the peak resident memory starts again from here
    _opened_paths = []
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            code = main(argv)
    finally:
        opened, _opened_paths = _opened_paths, None
    grown = status_bytes("VmHWM") - rss
    err = capfd.readouterr().err
    world_cache.clear_memory()
    return code, err, grown, opened


def check_answer(capfd, folder: str, name: str, *, strength: float = 1.0, rotation: float = 0.0,
                 study: bool = False) -> tuple[int, str]:
    """Render a preset in ``folder`` naming the environment image ``name`` (or a study of two variants
    of it, in this process) and check the answer."""
    doc = baseline_doc()
    doc["image"] = {"width": 8, "height": 8}
    doc["environment"] = {"world": "file", "file": name, "strength": strength, "rotation_deg": rotation}
    scene = os.path.join(folder, "scene.json")
    with open(scene, "w") as f:
        json.dump(doc, f)
    out_folder = tempfile.mkdtemp(dir=os.path.dirname(folder))
    if study:
        output = os.path.join(out_folder, "sheet.png")
        argv = ["study", scene, "--vary", "lens.ior=1.45,1.55", "--size", "8x8", "--workers", "0", "-o", output,
                "--save-variants", os.path.join(out_folder, "variants")]
    else:
        output = os.path.join(out_folder, "out.exr")
        argv = ["render", scene, "-o", output, "--samples", "1"]
    code, err, grown, opened = run_main(capfd, argv)
    assert code in (0, 2), (code, err)
    if currently_in_test_context():  # what --hypothesis-show-statistics counts
        said = re.sub(r"[0-9]+", "N", re.sub(r"(/tmp|'/tmp)\S*", "", err.split("environment.file: ")[-1]))
        event(f"exit {code}" + (f": {said.strip()[:70]}" if code else ""))
    assert "Traceback" not in err and "Warning" not in err, err
    image_path = os.path.join(folder, name)
    if code == 0:
        assert err == "", err  # nothing from OpenImageIO, OpenEXR or numpy either
        image, stored = imageio.read_image(output)
        assert np.isfinite(image).all(), "a non-finite pixel with exit 0"
        if study:
            assert sorted(os.listdir(out_folder)) == ["sheet.png", "variants"]
            assert len(os.listdir(os.path.join(out_folder, "variants"))) == 2
        else:
            assert stored["environment"]["file"] == name
        real = os.path.realpath(image_path)
        assert os.path.dirname(real) == os.path.realpath(folder), ("rendered an image outside the folder", name)
    else:
        lines = err.splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), err
        assert printable(lines[0], 10**6) == lines[0]
        assert "environment.file" in lines[0], lines[0]
        assert printable(name, 60)[:40] in lines[0] or printable(name, 200)[:40] in lines[0], (name, lines[0])
        assert os.listdir(out_folder) == []  # no sheet, no variants, nothing half-written
    roots = (os.path.realpath(folder), os.path.realpath(os.environ[world_cache.ENV_FOLDER]),
             os.path.realpath(out_folder))
    outside = [p for p in opened if os.path.realpath(p).startswith(os.path.dirname(os.path.realpath(folder)))
               and not os.path.realpath(p).startswith(roots)]
    assert not outside, ("read outside the preset's folder", outside)
    counted = _declared_bytes(image_path) if os.path.isfile(image_path) else 0
    bound = budget.render_bytes(8, 8, False, "exr", environment=counted) + (budget.BASE_BYTES if study else 0)
    assert grown <= bound, (f"peak grew {grown / MIB:.0f} MB, the render was checked against {bound / MIB:.0f} MB")
    shutil.rmtree(out_folder)
    return code, err


def library(space) -> str:
    folder = tempfile.mkdtemp(dir=space, prefix="lib-")
    return folder


# -- Radiance .hdr --------------------------------------------------------------------------------

SIZE = st.integers(1, 40)  # most headers declare a size that the pixels after them can hold
EDGE_SIZE = st.sampled_from([0, -1, -5, 2**15, 30000, 100000, 2**31 - 1, 2**31, 2**32 + 3, 2**63, 10**30])
FLOATS = st.one_of(st.floats(-1e3, 1e3), st.sampled_from([0.0, -0.0, 1e-40, 1e30, 1.7e38, 3e38, -3e38, 65504.0]))


def rgbe(values: np.ndarray) -> bytes:
    """Flat RGBE bytes of (n, 3) float values (Radiance's shared exponent: a mantissa byte per channel,
    exponent + 128; what does not fit is taken to the largest code)."""
    v = np.max(values, axis=1)
    mantissa, exponent = np.frexp(v)
    out = np.zeros((len(values), 4), np.uint8)
    ok = v > 1e-32
    scale = np.where(ok, mantissa * 256.0 / np.where(ok, v, 1.0), 0.0)
    with np.errstate(all="ignore"):
        out[:, :3] = np.clip(values * scale[:, None], 0, 255).astype(np.uint8)
    out[:, 3] = np.where(ok, np.clip(exponent + 128, 0, 255), 0)
    return out.tobytes()


@st.composite
def hdr_files(draw) -> bytes:
    magic = draw(st.sampled_from([b"#?RADIANCE"] * 12 + [b"#?RGBE", b"#?", b"#!RADIANCE", b"", b"RADIANCE"]))
    lines = [magic] + ([b"FORMAT=32-bit_rle_rgbe"] if draw(st.integers(0, 7)) else [])
    for _ in range(draw(st.integers(0, 2))):
        lines.append(draw(st.one_of(
            st.sampled_from([b"FORMAT=32-bit_rle_rgbe", b"FORMAT=32-bit_rle_xyze", b"FORMAT=", b"EXPOSURE=1e30",
                             b"EXPOSURE=-1", b"EXPOSURE=nan", b"GAMMA=0", b"PRIMARIES=1 1 1 1 1 1 1 1"]),
            st.binary(max_size=40).filter(lambda b: b"\n" not in b))))  # non-UTF-8 bytes in the header
    head = b"\n".join(lines) + b"\n\n"
    sizes = st.one_of(SIZE, SIZE, SIZE, EDGE_SIZE)
    height, width = draw(sizes), draw(sizes)
    order = draw(st.sampled_from([b"-Y %d +X %d"] * 6 + [b"+Y %d +X %d", b"-Y %d -X %d", b"+X %d -Y %d",
                                                         b"-Y %d  +X %d", b"-Y %dx +X %d"]))
    head += order % (height, width) + b"\n"
    if draw(st.integers(0, 5)) == 0:
        head = head.replace(b"\n", b"\r\n")
    h, w = max(0, min(height, 40)), max(0, min(width, 40))
    body = draw(st.sampled_from(["values"] * 4 + ["bytes", "rle", "none"]))
    if body == "values":
        values = np.array(draw(st.lists(st.tuples(FLOATS, FLOATS, FLOATS), min_size=1, max_size=8)), np.float64)
        pixels = rgbe(np.resize(values, (h * w, 3)))
        pixels = pixels[:draw(st.integers(0, len(pixels)))] if draw(st.integers(0, 3)) == 0 else pixels
    elif body == "bytes":
        pixels = draw(st.binary(max_size=4 * h * w + 8))
    elif body == "rle":  # new-style run-length scanlines: 2, 2, width; then runs (some of them lying)
        pixels = b""
        for _ in range(draw(st.integers(1, 3))):
            pixels += bytes([2, 2, (w >> 8) & 0x7F, w & 0xFF])
            pixels += draw(st.binary(max_size=24))
    else:
        pixels = b""
    return head + pixels


@pytest.mark.slow
@fuzz(200)
@given(data=hdr_files(), suffix=st.sampled_from([".hdr"] * 4 + [".HDR", ".exr"]),
       strength=st.sampled_from([0.0, 1.0, 10.0, 1e4]))
def test_any_radiance_file(space, capfd, data, suffix, strength):
    folder = library(space)
    name = "sky" + suffix
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data)
    check_answer(capfd, folder, name, strength=strength)


# -- OpenEXR ----------------------------------------------------------------------------------------

EXR_FORMATS = ["half", "float", "uint"]


def exr_bytes(folder: str, pixels: np.ndarray, fmt: str, tile: int, compression: str, origin: tuple[int, int],
              names: list[str]) -> bytes:
    """An OpenEXR file of ``pixels`` (h, w, c) written by OpenImageIO, as bytes."""
    oiio = imageio.oiio_module()
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, {"half": oiio.HALF, "float": oiio.FLOAT, "uint": oiio.UINT}[fmt])
    spec.x, spec.y = origin
    spec.full_x, spec.full_y, spec.full_width, spec.full_height = 0, 0, w, h
    spec.channelnames = tuple(names)
    spec.attribute("compression", compression)
    if tile:
        spec.tile_width = spec.tile_height = tile
    path = os.path.join(folder, "made.exr")
    out = oiio.ImageOutput.create(path)
    assert out.open(path, spec), out.geterror()
    data = pixels.astype(np.float32)
    if fmt == "uint":
        data = np.nan_to_num(np.clip(data, 0, 4e9), nan=0.0)
    assert out.write_image(data), out.geterror()
    out.close()
    with open(path, "rb") as f:
        raw = f.read()
    os.remove(path)
    return raw


def damaged(draw, raw: bytes) -> bytes:
    raw = bytearray(raw)
    how = draw(st.sampled_from(["none", "none", "flip", "cut", "splice", "window"]))
    if how == "flip":
        for _ in range(draw(st.integers(1, 8))):
            raw[draw(st.integers(0, len(raw) - 1))] = draw(st.integers(0, 255))
    elif how == "cut":
        raw = raw[:draw(st.integers(0, len(raw)))]
    elif how == "splice":
        at = draw(st.integers(4, len(raw)))
        raw[at:at] = draw(st.binary(min_size=1, max_size=64))
    elif how == "window":  # the dataWindow's four ints (box2i) replaced: sizes huge, negative, zero
        at = raw.find(b"dataWindow\0box2i\0")
        if at >= 0:
            at += len(b"dataWindow\0box2i\0") + 4
            edge = st.sampled_from([0, -1, 1, 7, 16383, 16384, 8191, 30000, 2**31 - 1, -(2**31)])
            raw[at:at + 16] = struct.pack("<4i", *(draw(edge) for _ in range(4)))
    return bytes(raw)


@st.composite
def exr_files(draw, folder: str) -> bytes:
    h, w = draw(st.integers(1, 24)), draw(st.integers(1, 24))
    c = draw(st.integers(1, 6))
    names = draw(st.sampled_from([["R", "G", "B", "A", "Z", "Y"], ["Y", "A", "R", "G", "B", "Z"],
                                  ["A", "B", "C", "D", "E", "F"], ["diffuse.R", "diffuse.G", "diffuse.B", "R", "G",
                                                                   "B"]]))[:c]
    edge = st.sampled_from([0.0, -0.0, 1.0, 0.5, -1.0, 65504.0, 1e5, 1e30, 3e38, -3e38, float("nan"), float("inf"),
                            -float("inf"), 1e-45])
    values = np.array(draw(st.lists(edge, min_size=1, max_size=12)), np.float32)
    pixels = np.resize(values, (h, w, c))
    raw = exr_bytes(folder, pixels, draw(st.sampled_from(EXR_FORMATS)), draw(st.sampled_from([0, 0, 4, 16])),
                    draw(st.sampled_from(["none", "zip", "piz", "rle", "b44", "dwaa"])),
                    draw(st.sampled_from([(0, 0), (0, 0), (3, -2), (-100, 5)])), names)
    return damaged(draw, raw)


@pytest.mark.slow
@fuzz(200)
@given(data=st.data(), suffix=st.sampled_from([".exr", ".EXR", ".hdr"]), strength=st.sampled_from([1.0, 10.0, 1e4]))
def test_any_openexr_file(space, capfd, data, suffix, strength):
    folder = library(space)
    raw = data.draw(exr_files(folder))
    name = "sky" + suffix
    with open(os.path.join(folder, name), "wb") as f:
        f.write(raw)
    check_answer(capfd, folder, name, strength=strength, rotation=data.draw(st.sampled_from([0.0, 90.0, -360.0])))


@pytest.mark.slow
@fuzz(40)
@given(data=st.data(), kind=st.sampled_from(["hdr", "exr"]))
def test_any_image_in_a_study(space, capfd, data, kind):
    folder = library(space)
    raw = data.draw(hdr_files() if kind == "hdr" else exr_files(folder))
    with open(os.path.join(folder, "sky." + kind), "wb") as f:
        f.write(raw)
    check_answer(capfd, folder, "sky." + kind, strength=data.draw(st.sampled_from([1.0, 1e4])), study=True)


@pytest.mark.slow
@fuzz(60)
@given(data=st.binary(max_size=300), magic=st.sampled_from([b"", b"\x76\x2f\x31\x01", b"#?RADIANCE\n", b"\x89PNG",
                                                             b"II*\0", b"\xff\xd8\xff", b"GIF89a", b"P6\n"]),
       suffix=st.sampled_from([".exr", ".hdr"]))
def test_any_bytes_under_any_first_bytes(space, capfd, data, magic, suffix):
    folder = library(space)
    name = "sky" + suffix
    with open(os.path.join(folder, name), "wb") as f:
        f.write(magic + data)
    check_answer(capfd, folder, name)


@fuzz(20)
@given(kind=st.sampled_from(["png", "tif", "jpg", "bmp"]), suffix=st.sampled_from([".exr", ".hdr"]))
def test_an_image_of_another_format_under_an_environment_name_is_refused(space, capfd, kind, suffix):
    folder = library(space)
    oiio = imageio.oiio_module()
    made = os.path.join(folder, "made." + kind)
    buf = oiio.ImageBuf(oiio.ImageSpec(16, 8, 3, oiio.UINT8))
    assert buf.write(made), buf.geterror()
    os.replace(made, os.path.join(folder, "sky" + suffix))
    code, err = check_answer(capfd, folder, "sky" + suffix)
    assert code == 2 and "neither an OpenEXR nor a Radiance file" in err, err


# -- where the file is ----------------------------------------------------------------------------

SKY = np.linspace(0.2, 2.0, 16 * 32 * 3, dtype=np.float32).reshape(16, 32, 3)


@pytest.mark.slow
@fuzz(80)
@given(form=st.sampled_from(["absolute", "dotdot", "dotdot-inside", "symlink-out", "symlink-in", "symlink-loop",
                             "folder", "dot", "hidden", "home", "nul", "backslash", "spaces", "plain", "fifo",
                             "directory", "missing", "long"]),
       non_utf8=st.booleans(), suffix=st.sampled_from([".exr", ".hdr"]))
def test_any_path_form(space, capfd, form, non_utf8, suffix):
    root = tempfile.mkdtemp(dir=space, prefix="paths-")
    folder = os.path.join(root, os.fsdecode(b"team \xff") if non_utf8 else "team")
    outside = os.path.join(root, "outside")
    os.makedirs(os.path.join(folder, "sub"))
    os.makedirs(outside)
    far = os.path.join(outside, "far" + suffix)  # valid: a render that reached it would exit 0
    write_sky(far)
    for near in (os.path.join(folder, "sub", "near" + suffix), os.path.join(folder, "near" + suffix)):
        shutil.copy(far, near)
    name = {"absolute": far, "dotdot": "../outside/far", "dotdot-inside": "sub/../near", "folder": "sub/near",
            "dot": "./near", "hidden": ".near", "home": "~/near", "nul": "near\0", "backslash": "sub\\near",
            "spaces": " near", "long": "n" * 300}.get(form, "sky")
    name += "" if form == "absolute" else suffix
    made = os.path.join(folder, name)
    if form == "symlink-out":
        os.symlink(far, made)
    elif form == "symlink-in":
        os.symlink("near" + suffix, made)
    elif form == "symlink-loop":
        os.symlink(name, made)
    elif form == "plain":
        shutil.copy(far, made)
    elif form == "fifo":
        os.mkfifo(made)
    elif form == "directory":
        os.makedirs(made)
    code, err = check_answer(capfd, folder, name)
    assert code == (0 if form in ("plain", "symlink-in") else 2), (form, err)


def write_sky(path: str) -> None:
    """SKY as an .exr or .hdr file (written under a UTF-8 name, then moved)."""
    oiio = imageio.oiio_module()
    buf = oiio.ImageBuf(oiio.ImageSpec(32, 16, 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(0, 32, 0, 16), SKY)
    made = tempfile.mktemp(suffix=os.path.splitext(path)[1])
    assert buf.write(made), buf.geterror()
    shutil.move(made, path)


def test_a_library_folder_whose_name_is_not_utf8_renders_its_image(space, capfd):
    # OpenImageIO takes only UTF-8 names: such a path is opened here and handed over as /dev/fd/N.
    folder = os.path.join(space, os.fsdecode(b"team \xff"))
    os.makedirs(folder)
    write_sky(os.path.join(folder, "sky.exr"))
    code, err = check_answer(capfd, folder, "sky.exr")
    assert code == 0, err
    np.testing.assert_array_equal(world_image.pixels_of(world_image.read_padded(os.path.join(folder, "sky.exr")),
                                                        32, 16), SKY)


def test_a_message_holding_bytes_that_are_not_utf8_is_one_line(space, capfd):
    # Found by the fuzz suite: OpenEXR's message quoted a damaged header's bytes, and pybind11's
    # UnicodeDecodeError left the renderer as a traceback.
    folder = library(space)
    raw = exr_bytes(folder, SKY, "float", 0, "zip", (0, 0), ["R", "G", "B"])
    assert raw.count(b"lineOrder\0lineOrder\0") == 1
    with open(os.path.join(folder, "sky.exr"), "wb") as f:
        f.write(raw.replace(b"lineOrder\0lineOrder\0", b"lineOrder\0lineOrd\xe9r\0"))
    code, err = check_answer(capfd, folder, "sky.exr")
    assert code == 2 and "lineOrd\\xe9r" in err, err


def test_a_tile_declared_wider_than_memory_is_counted_before_it_is_read(space, capfd):
    # Found by the fuzz suite: a 1 x 1 image whose tiles were declared 3,538,948 px wide took 233 MB
    # to read, counted as nothing; 2**25-wide tiles would take 4 GB.
    folder = library(space)
    raw = bytearray(exr_bytes(folder, SKY[:1, :1], "float", 4, "zip", (0, 0), ["R", "G", "B"]))
    at = raw.index(b"tiles\0tiledesc\0") + len(b"tiles\0tiledesc\0") + 4
    for width, said in ((3538948, None), (2**25, "would take")):
        raw[at:at + 4] = struct.pack("<I", width)
        with open(os.path.join(folder, "sky.exr"), "wb") as f:
            f.write(bytes(raw))
        code, err = check_answer(capfd, folder, "sky.exr")  # within what was counted
        if said:
            assert code == 2 and said in err and f"tiles of {width}x4 px" in err, err
        else:
            assert world_image.header(os.path.join(folder, "sky.exr"))[3] == width


def test_an_exr_damaged_inside_its_pixels_says_nothing_on_stderr_but_one_line(space, capfd):
    # Found by the fuzz suite: OpenImageIO's first OpenEXR reader let OpenEXR print its own messages
    # ("EXR_ERR_BAD_CHUNK_LEADER ...") on stderr beside the render's answer.
    folder = library(space)
    raw = bytearray(exr_bytes(folder, np.resize(SKY, (16, 32, 3)), "float", 0, "zip", (0, 0), ["R", "G", "B"]))
    raw[len(raw) // 2:] = bytes(len(raw) - len(raw) // 2)
    with open(os.path.join(folder, "sky.exr"), "wb") as f:
        f.write(bytes(raw))
    check_answer(capfd, folder, "sky.exr")
