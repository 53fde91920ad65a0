"""What the tests share: the project's folders, the command line in a subprocess, and small scenes
built for the tracer's tests (each isolates one part of the model)."""

from __future__ import annotations

import ast
import contextlib
import copy
import json
import math
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from hypothesis import settings

from core_tracer import SceneError
from core_tracer.checkpoints import ENV_MARKER, ENV_POINT
from core_tracer.scene.validate import parse_scene

ROOT = Path(__file__).resolve().parent.parent
PRESETS = ROOT / "presets"
BASELINE = PRESETS / "paper-baseline.json"
FOUR_LAMPS = PRESETS / "four-lamp-rear-combination.json"
# The built-in presets that are parametric designs only (the free-form example carries its meshes in a
# .glb beside it and is tested on its own: tests/addon/test_addon_freeform_example.py).
PARAMETRIC_PRESETS = sorted(p for p in PRESETS.glob("*.json") if '"freeform"' not in p.read_text(encoding="utf-8"))


# LAMP_FUZZ_EXAMPLES=N multiplies the inputs of every fuzz test by N for a long run.
FUZZ_SCALE = max(1, int(os.environ.get("LAMP_FUZZ_EXAMPLES", "1")))


def fuzz(examples: int) -> settings:
    """Hypothesis settings of a fuzz test: ``examples`` per run (times LAMP_FUZZ_EXAMPLES), under the
    ``lamp`` profile of tests/conftest.py (no example database, no deadline)."""
    return settings(max_examples=examples * FUZZ_SCALE)


def cli_command(*args: str | Path) -> list[str]:
    """The command line of ``python -m core_tracer ARGS``."""
    return [sys.executable, "-m", "core_tracer", *map(str, args)]


def run_cli(*args: str | Path, timeout: float = 300, env: dict | None = None, prefix: tuple[str, ...] = (),
            text: bool = True) -> subprocess.CompletedProcess:
    """``python -m core_tracer ARGS`` from the repository root, output captured (as text unless
    ``text`` is false); ``prefix`` goes before the interpreter (``prlimit ...``)."""
    return subprocess.run([*prefix, *cli_command(*args)], cwd=ROOT, capture_output=True, text=text,
                          timeout=timeout, env=env)


def start_cli_at(point: str, marker: Path, *args: str | Path, env: dict | None = None) -> subprocess.Popen:
    """Start ``python -m core_tracer ARGS`` and return once it has reached the checkpoint ``point``
    (``core_tracer/checkpoints.py``), where it waits for the test's SIGINT or SIGTERM: a signal then
    lands at that point however fast or slow the machine is. ``marker`` is the file it creates there."""
    env = dict(os.environ if env is None else env, **{ENV_POINT: point, ENV_MARKER: str(marker)})
    proc = subprocess.Popen(cli_command(*args), cwd=ROOT, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    try:
        while not marker.exists():
            assert proc.poll() is None, proc.communicate()
            assert time.monotonic() < deadline, "the program never reached " + point
            time.sleep(0.01)
    except BaseException:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        raise
    return proc


def signal_and_wait(proc: subprocess.Popen, sig: int) -> tuple[str, str]:
    """Send ``sig`` to a program started by ``start_cli_at`` and wait for it to end (killed if it
    has not within two minutes); its (stdout, stderr)."""
    try:
        proc.send_signal(sig)
        return proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def child_pids(pid: int) -> list[int]:
    """Process ids whose parent is ``pid`` (Linux /proc)."""
    out = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        out += [int(c) for c in (task / "children").read_text().split()]
    return out


def descendants(pid: int) -> list[int]:
    """Every process started by ``pid`` and by those, from /proc."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        try:
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    kids = [int(c) for c in f.read().split()]
                out += kids
                todo += kids
        except FileNotFoundError:
            continue
    return out


def process_gone(pid: int) -> bool:
    """Whether the process ``pid`` has ended (a zombie waiting for its parent has)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return True
    return state == "Z"


def assert_bad_input(proc: subprocess.CompletedProcess, *needles: str) -> str:
    """Exit 2, exactly one line on stderr containing every needle, no traceback."""
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


def baseline_doc() -> dict:
    return json.loads(BASELINE.read_text())


def scene_with(**edits) -> dict:
    """The paper baseline with dotted-path edits, e.g. ``scene_with(**{"lamps[0].cuts.height": 0})``."""
    doc = copy.deepcopy(baseline_doc())
    for path, value in edits.items():
        node = doc
        parts = path.replace("]", "").replace("[", ".").split(".")
        for part in parts[:-1]:
            node = node[int(part)] if part.isdigit() else node.setdefault(part, {})
        last = parts[-1]
        if value is None:
            node.pop(last, None)
        else:
            node[last] = value
    return parse_scene(doc)


NUMBER = r"-?[0-9.]+(?:e[-+]?[0-9]+)?"  # a number in a message


def allowed_ranges(message: str) -> list[tuple[float, float]]:
    """Every closed or half-open range [a, b] / (a, b] after "allowed" in a message."""
    allowed = message[message.index("allowed"):]
    return [(float(a), float(b)) for a, b in re.findall(rf"[\[(]({NUMBER}), ({NUMBER})[\])]", allowed)]


def random_lamp_doc(doc: dict, rng) -> dict:
    """``doc`` with the body's and lamp 0's numbers drawn from wide but plausible ranges (a round lens's
    radius, or a rectangular lens's width, height and corner radius), in place."""
    lamp = doc["lamps"][0]
    doc["body"]["size"] = [rng.uniform(20, 300), rng.uniform(20, 200)]
    doc["body"]["depth"] = rng.uniform(2, 150)
    lamp["center"] = [rng.uniform(-60, 60), rng.uniform(-40, 40)]
    if lamp["lens"].get("outline") == "rectangular":
        w, h = rng.uniform(5, 160), rng.uniform(5, 120)
        lamp["lens"].update(width=w, height=h, corner_radius=rng.uniform(0, min(w, h) / 2 * 1.2))
    else:
        lamp["lens"]["radius"] = rng.uniform(5, 80)
    lamp["lens"]["thickness"] = rng.uniform(0.5, 8)
    lamp["cuts"]["pitch"] = rng.uniform(1, 40)
    lamp["cuts"]["height"] = rng.uniform(0, 15)
    lamp["reflector"]["focal_length"] = rng.uniform(2, 60)
    lamp["reflector"]["gap"] = rng.uniform(0, 10)
    lamp["bulb"]["radius"] = rng.uniform(1, 30)
    lamp["bulb"]["offset"] = [rng.uniform(-20, 20), rng.uniform(-30, 30), rng.uniform(-20, 20)]
    lamp["socket"]["radius"] = rng.uniform(1, 20)
    return doc


def follow_message(doc: dict, err: SceneError) -> None:
    """Change the field ``err`` names (of lamp 0 or the body) to a value from the range it gives, in place:
    the top of the range for sizes, the bottom otherwise, just inside an open top; a bulb moved too far
    sideways is brought back to the distance the message states, in the same direction."""
    lamp = doc["lamps"][0]
    ranges = allowed_ranges(err.message)
    field = err.path.removeprefix("lamps[0].")
    if field == "body.size":
        doc["body"]["size"] = [ranges[0][0], ranges[1][0]]
    elif field == "center":
        lamp["center"] = [ranges[0][0], ranges[1][0]]
    elif field == "bulb.offset" and ranges:
        lamp["bulb"]["offset"][1] = sum(ranges[0]) / 2
    elif field == "bulb.offset":
        limit = float(re.search(rf"up to ({NUMBER}) mm", err.message)[1])
        y = float(re.search(rf"at y = ({NUMBER}) mm", err.message)[1])
        x, _, z = lamp["bulb"]["offset"]
        scale = limit / math.hypot(x, z)
        lamp["bulb"]["offset"] = [x * scale, y, z * scale]
    else:
        section, key = field.split(".")
        node = doc["body"] if section == "body" else lamp[section]
        lo, hi = ranges[0]
        if section == "socket":  # an open range (0, hi)
            hi *= 0.99
        node[key] = hi if key in ("height", "pitch", "radius", "corner_radius", "width") else lo


def dark_clear_lens_doc(reflector: dict) -> dict:
    """The baseline document with its lamp reduced to a flat clear lens (no cuts, no absorption, no
    surface shading, a black side wall) over a reflector of ``reflector``'s values, the bulb off, a
    black socket and body, no sun, and the camera low on the left looking at the lens obliquely."""
    doc = baseline_doc()
    lamp = doc["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"].update(absorption=[0.0, 0.0, 0.0], diffuse_color=[0.0, 0.0, 0.0], specular=0.0,
                        side_wall_color=[0.0, 0.0, 0.0])
    lamp["reflector"].update(reflector)
    lamp["bulb"]["on"] = False
    lamp["socket"]["color"] = [0.0, 0.0, 0.0]
    doc["body"]["color"] = [0.0, 0.0, 0.0]
    doc["light"] = {"direction": [0.3, -1.0, 0.6], "color": [1, 1, 1], "ambient": 0.0, "strength": 0.0}
    doc["camera"] = {"position": [-260, -700, -160], "target": [0, 0, 0], "up": [0, 0, 1], "fov_deg": 9.0}
    return doc


def flat_lens_on_axis(ior: float = 1.49, absorption=(0.0, 0.0, 0.0), intensity=(8.0, 7.0, 6.0),
                      thickness: float = 3.0) -> dict:
    """A flat lens (no cuts) seen straight on by an orthographic camera: the centre pixel sees the
    bulb at normal incidence, with no lens-surface shading and no reflector in the way."""
    return scene_with(**{
        "camera": {"type": "orthographic", "position": [0, -500, 0], "target": [0, 0, 0], "up": [0, 0, 1],
                   "width": 20.0},
        "image": {"width": 9, "height": 9},
        "lamps[0].cuts.height": 0.0,
        "lamps[0].lens.ior": ior,
        "lamps[0].lens.thickness": thickness,
        "lamps[0].lens.absorption": list(absorption),
        "lamps[0].lens.specular": 0.0,
        "lamps[0].lens.diffuse_color": [0.0, 0.0, 0.0],
        "lamps[0].bulb.intensity": list(intensity),
    })


def sibling_imports(path: Path) -> set[str]:
    """The sibling modules a module imports, at the top or inside functions (``from . import x``,
    ``from .x import y``)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.level == 1:
            if node.module:
                out.add(node.module.split(".")[0])
            else:
                out.update(alias.name for alias in node.names)
    return out


def package_imports(package: Path) -> dict[str, set[str]]:
    """The modules of ``package`` (a folder, sub-packages included) by dotted name below it
    (``"design.properties"``, a sub-package's ``__init__`` as ``"design"``), each with the modules of
    the package it imports, at the top or inside functions, relative imports resolved
    (``from ..design import properties`` is ``"design.properties"``)."""
    paths = {}
    for path in package.rglob("*.py"):
        parts = path.relative_to(package).with_suffix("").parts
        paths[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    graph = {}
    for name, path in paths.items():
        here = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
        here = [p for p in here if p]
        out = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:
                base = here[: len(here) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
                for full in [target] + [f"{target}.{a.name}".lstrip(".") for a in node.names]:
                    if full in paths and full != name and paths[full].name != "__init__.py":
                        out.add(full)
        graph[name] = out
    return graph


def fresnel_unpolarised(cos_i: float, n: float) -> float:
    """Fresnel reflectance of unpolarised light from air into index ``n``, written out here
    independently of ``optics`` (the mean of the s and p reflectances)."""
    import math

    sin_t = math.sqrt(1 - cos_i * cos_i) / n
    cos_t = math.sqrt(1 - sin_t * sin_t)
    rs = (cos_i - n * cos_t) / (cos_i + n * cos_t)
    rp = (n * cos_i - cos_t) / (n * cos_i + cos_t)
    return 0.5 * (rs * rs + rp * rp)


def write_exr(path, pixels) -> str:
    """An RGB float EXR of ``pixels`` (H, W, 3), written with OpenImageIO; returns its path."""
    import numpy as np

    from core_tracer.images import imageio

    oiio = imageio.oiio_module()
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], 3, oiio.FLOAT)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec)
    assert out.write_image(np.asarray(pixels, np.float32))
    out.close()
    return str(path)


def slab_series(r: float, transmittance, cutoff: float):
    """Bulb luminance factor through a slab, bouncing inside it, walked with the paper's cut-off.

    The eye ray enters with 1 - r; each pass through the lens multiplies by T. At the inner face
    the ray splits: (1 - r) goes on to the bulb, r goes back; at the outer face r comes back in.
    A branch is traced only while its accumulated attenuation (max over RGB) is >= ``cutoff``.
    """
    import numpy as np

    # R, G, B; or as many channels as ``r`` or ``transmittance`` give (the photometric mode's bands)
    channels = np.broadcast(np.asarray(r, float), np.asarray(transmittance, float)).shape or (3,)
    total = np.zeros(channels)
    k = np.broadcast_to(1.0 - np.asarray(r, float), channels)  # inside the lens, heading to the inner face
    while True:
        k = k * transmittance  # cross the lens
        to_bulb = k * (1.0 - r)
        if to_bulb.max() >= cutoff:
            total += to_bulb
        back = k * r
        if back.max() < cutoff:
            break
        back = back * transmittance  # cross back to the outer face
        k = back * r
        if k.max() < cutoff:
            break
    return total


def slab_luminance(lamp: dict, absorption):
    """The bulb seen on the axis through the lamp's flat lens: its intensity times the slab transmittance
    (1 - r)^2 tau / (1 - r^2 tau^2), every internal reflection summed (r at normal incidence,
    tau = exp(-absorption * thickness))."""
    import numpy as np

    lens = lamp["lens"]
    r = ((lens["ior"] - 1) / (lens["ior"] + 1)) ** 2
    tau = np.exp(-np.asarray(absorption) * lens["thickness"])
    return np.asarray(lamp["bulb"]["intensity"]) * (1 - r) ** 2 * tau / (1 - r * r * tau * tau)


def smooth_sky(width: int, height: int):
    """A smooth, everywhere-different equirectangular sky (height, width, 3)."""
    import numpy as np

    cols, rows = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    lon, lat = cols / width * 2 * np.pi, (0.5 - rows / height) * np.pi
    return np.stack([1.0 + 0.5 * np.sin(lon), 1.0 + 0.5 * np.cos(lon) * np.cos(lat), 1.2 + 0.6 * np.sin(lat)], -1)


def render_engine_exr(bl_scene, path):
    """Render ``bl_scene`` with its engine (F12) and read the result back from a 32-bit EXR at ``path``:
    its pixels (height, width, channels)."""
    import bpy
    import numpy as np
    import OpenImageIO as oiio

    settings = bl_scene.render.image_settings
    settings.file_format = "OPEN_EXR"
    settings.color_depth = "32"
    bpy.ops.render.render()
    bpy.data.images["Render Result"].save_render(str(path), scene=bl_scene)
    buf = oiio.ImageBuf(str(path))
    return np.asarray(buf.get_pixels(oiio.FLOAT)).reshape(buf.spec().height, buf.spec().width, -1)


def assert_lens_materials(scene: dict, lens_object, index: int) -> None:
    """Lamp ``index``'s lens object carries the lens and side-wall materials, with the design's side-wall
    colour and index of refraction."""
    import bpy
    import pytest

    lamp, name = scene["lamps"][index], f"Lamp {index + 1}"
    assert [m.name for m in lens_object.data.materials] == [f"{name} Lens", f"{name} Side Wall"]
    wall = bpy.data.materials[f"{name} Side Wall"]
    assert list(wall.node_tree.nodes["Side Wall BSDF"].inputs["Color"].default_value)[:3] == pytest.approx(
        lamp["lens"]["side_wall_color"])
    assert bpy.data.materials[f"{name} Lens"].node_tree.nodes["Lens BSDF"].inputs["IOR"].default_value == \
        pytest.approx(lamp["lens"]["ior"], rel=1e-6)


def creases(image, contrast_limit: float = 0.10):
    """Pixels of ``image`` (H, W, 3) that differ from one of their 8 neighbours by more than
    ``contrast_limit`` of their own value: silhouettes and cut creases, where a mesh and the
    analytic surface may rightly disagree by a pixel."""
    import numpy as np

    value = np.maximum(image.max(axis=2), 1e-3 * image.max())
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = image.shape[:2]
    contrast = np.zeros((h, w))
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            neighbour = padded[1 + dy:h + 1 + dy, 1 + dx:w + 1 + dx]
            contrast = np.maximum(contrast, np.abs(neighbour - image).max(axis=2) / value)
    return contrast > contrast_limit



def status_bytes(field: str) -> int:
    """A memory figure of this process from /proc/self/status (``VmRSS``, ``VmHWM``), in bytes."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) * 1024
    raise AssertionError(field)


def write_tile_bomb(path: Path) -> None:
    """A 1 x 1 px tiled OpenEXR at ``path`` whose tiles are declared 2**25 px wide (4 GB if believed)."""
    import struct

    import numpy as np

    from core_tracer.images.imageio import oiio_module

    oiio = oiio_module()
    made = path.with_name("made.exr")
    spec = oiio.ImageSpec(1, 1, 3, oiio.FLOAT)
    spec.tile_width = spec.tile_height = 4
    out = oiio.ImageOutput.create(str(made))
    assert out.open(str(made), spec)
    assert out.write_image(np.ones((1, 1, 3), np.float32))
    out.close()
    raw = bytearray(made.read_bytes())
    at = raw.index(b"tiles\0tiledesc\0") + len(b"tiles\0tiledesc\0") + 4
    raw[at:at + 4] = struct.pack("<I", 2**25)
    path.write_bytes(bytes(raw))
    made.unlink()


def whole_report(error: str, out: str) -> str:
    """The whole text of an operator's error report: ``error`` (the RuntimeError Blender raises with the
    one-line report) unless it was cut to one line ("... (Info editor)"); then its lines in the Info
    editor (``lamp_addon.reports.details``, printed as "Info: ..." in ``out``) joined again."""
    if "(Info editor)" not in error:
        return error
    return " ".join(line.removeprefix("Info: ") for line in out.splitlines() if line.startswith("Info: "))


@contextlib.contextmanager
def small_and_large_worker(small_mb: int = 200):
    """A local Dask cluster of one worker with ``small_mb`` MB and one started beside it with 2 GiB,
    as `dask worker --memory-limit` starts a studio's node: yields (client, small, large), the
    workers' addresses; the large worker is stopped on the way out."""
    from core_tracer.cluster import engine

    with engine.connect(workers=1, memory_limit=small_mb * 2**20) as client:
        small = next(iter(client.scheduler_info()["workers"]))
        big = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", client.scheduler.address,
                                "--nthreads", "1", "--memory-limit", "2GiB", "--no-dashboard", "--preload",
                                engine.PRELOAD], cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                               env={**os.environ, "PYTHONPATH": str(ROOT)})
        try:
            client.wait_for_workers(2, timeout=60)
            large = next(a for a in client.scheduler_info()["workers"] if a != small)
            yield client, small, large
        finally:
            big.terminate()
            big.wait(timeout=30)



STOP_LAMP = PRESETS / "photometric-stop-lamp.json"


def lit_lens_ratios(shown):
    """(G/R, B/R, pixels): the medians over the lit lens of a picture as shown (H, W, 3 display values
    in [0, 1], or linear): the pixels whose red is above half the picture's brightest red, leaving out
    neutral greys (a sheet's background and labels: R, G and B within 0.02 of each other). A red stop
    lamp shows G/R and B/R well below 0.5; its XYZ taken for R, G, B shows it gold (G/R ~0.7 and more)."""
    import numpy as np

    rgb = np.asarray(shown, np.float64)[..., :3]
    red = rgb[..., 0]
    neutral = (np.abs(red - rgb[..., 1]) < 0.02) & (np.abs(red - rgb[..., 2]) < 0.02)
    lit = (red > 0.5 * red[~neutral].max()) & ~neutral
    r = red[lit]
    return float(np.median(rgb[..., 1][lit] / r)), float(np.median(rgb[..., 2][lit] / r)), int(lit.sum())


def bare_led_document(*, depth_mm: float, die_mm: float, window_radius: float, window_thickness: float,
                      body: tuple[float, float, float], **led) -> dict:
    """The photometric stop lamp made into one LED die facing the lens (−y), ``depth_mm`` behind a
    window that is not there (index 1.0001, clear, no cuts: tests/measures/conftest.py), at night with
    no light but the die's; ``led`` sets further fields of the LED section (the spectrum is red)."""
    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text())
    doc["light"] = {"direction": [0.3, -1.0, 0.6], "ambient": 0.0, "illuminance_lux": 0.0}
    doc["environment"] = {"world": "none"}
    doc["body"] = {**doc["body"], "size": [body[0], body[1]], "depth": body[2]}
    lamp = doc["lamps"][0]
    lamp["cuts"]["height"] = 0.0
    lamp["lens"] = {**lamp["lens"], "material": "custom", "ior": 1.0001, "abbe": 100.0, "filter": "clear",
                    "radius": window_radius, "thickness": window_thickness, "specular": 0.0,
                    "diffuse_color": [0.0, 0.0, 0.0]}
    lamp["source"] = "led"
    lamp["led"] = {"position": [0.0, depth_mm, 0.0], "die_size": [die_mm, die_mm], "spectrum": "red_led", **led}
    return doc


def build_parts(lamp_addon, bl_scene, scene: dict) -> dict:
    """Build a normalised ``scene`` in ``bl_scene`` with the Build operator: its objects by lamp part."""
    import bpy

    lamp_addon.design.properties.scene_to_design(bl_scene, scene)
    assert bpy.ops.lamp.build() == {"FINISHED"}
    return {obj.get("lamp_part"): obj for obj in bl_scene.objects if obj.get("lamp_part")}


def local_mm(obj, lamp: dict):
    """The vertices (N, 3) of a built object in mm in its lamp's frame (x, z from the lens axis)."""
    import numpy as np

    n = len(obj.data.vertices)
    co = np.empty(n * 3, dtype=np.float32)
    obj.data.vertices.foreach_get("co", co)
    m = np.array(obj.matrix_world)
    world = (co.reshape(-1, 3).astype(np.float64) @ m[:3, :3].T + m[:3, 3]) * 1000.0
    cx, cz = lamp["center"]
    return world - np.array([cx, 0.0, cz])


def applied_preset(preset: Path):
    """Blender's startup file with ``preset`` applied from the preset browser; the scene."""
    import bpy

    bpy.ops.wm.read_homefile(use_factory_startup=True)
    bpy.ops.lamp.preset_refresh()
    wm = bpy.context.window_manager
    listed = [item.file for item in wm.lamp_presets]
    wm.lamp_presets_index = next(i for i, f in enumerate(listed) if f.endswith(preset.name))
    assert bpy.ops.lamp.preset_apply() == {"FINISHED"}
    return bpy.context.scene
