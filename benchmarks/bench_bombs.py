"""Bombs: small hostile files that declare much more than they hold, rendered by the command line
(issue 21). For each, the exit status, the wall time and the peak resident memory of the process.

    .venv/bin/python benchmarks/bench_bombs.py [--only NAME,NAME] [--size 8]

Each case is a preset beside its file, rendered in a fresh process with its own world cache
(``python -m core_tracer render SCENE -o OUT.exr --width 8 --height 8``); the peak is the child's
``ru_maxrss`` (``os.wait4``), the wall time includes the interpreter's start. The files are made
in another process (``--make``): a child's ``ru_maxrss`` starts from its parent's peak, and the
16384 x 8192 image takes 1.6 GB to make. The real images
(OpenEXR 16384 x 8192 and 8192 x 4096) are rendered a second time with the world cache their first
run left ("cached"). A bomb's answer must be exit 2 in a fraction of a second at the interpreter's
own size; a real image exit 0 within the budget its header was counted for.
"""

from __future__ import annotations

import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))  # the tile bomb the Blender test makes too
from helpers import write_tile_bomb  # noqa: E402

BASELINE = json.loads((ROOT / "presets" / "paper-baseline.json").read_text())
HDR_HEAD = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
JSON_CHUNK, BIN_CHUNK = 0x4E4F534A, 0x004E4942
FREEFORM = {"mesh_file": "lamp.glb", "parts": [{"object": "Lens", "role": "lens"}]}


def oiio_module():
    from core_tracer.images.imageio import oiio_module as module  # only in the process that makes the files

    return module()


def hdr(height: int, width: int, size: int) -> bytes:
    """A Radiance header declaring ``width`` x ``height`` px, padded with pixel bytes to ``size``."""
    head = HDR_HEAD + b"-Y %d +X %d\n" % (height, width)
    return head + b"\x80\x80\x80\x81" * ((size - len(head)) // 4) + b"\x80" * ((size - len(head)) % 4)


def exr(path: Path, width: int, height: int, constant: bool) -> None:
    """An OpenEXR of ``width`` x ``height`` px (half, zip): one value everywhere, or a sky with a sun."""
    import numpy as np

    oiio = oiio_module()
    spec = oiio.ImageSpec(width, height, 3, oiio.HALF)
    spec.attribute("compression", "zip")
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), out.geterror()
    if constant:
        pixels = np.full((height, width, 3), 0.5, np.float32)
    else:
        pixels = np.linspace(1.0, 0.2, height, dtype=np.float32)[:, None, None] * np.ones((1, width, 3), np.float32)
        pixels[height // 4:height // 4 + 8, width // 3:width // 3 + 8] = 5000.0
    assert out.write_image(pixels), out.geterror()
    out.close()


def glb(doc: dict, blob: bytes = b"", extra: bytes = b"") -> bytes:
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), JSON_CHUNK) + text
    if blob:
        body += struct.pack("<II", len(blob), BIN_CHUNK) + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body) + len(extra)) + body + extra


def box_glb(scale: float) -> bytes:
    """A 40 x 3 x 40 mm box named Lens under a node of this ``scale``."""
    import numpy as np

    corners = np.array([[x, y, z] for x in (-0.02, 0.02) for y in (0.0, 0.003) for z in (-0.02, 0.02)], np.float32)
    faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                      [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]], np.uint16)
    blob = corners.tobytes() + faces.tobytes()
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"name": "Lens", "mesh": 0, "scale": [scale] * 3}],
           "meshes": [{"name": "Lens", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "buffers": [{"byteLength": len(blob)}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96},
                           {"buffer": 0, "byteOffset": 96, "byteLength": 72}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                          "min": corners.min(axis=0).tolist(), "max": corners.max(axis=0).tolist()},
                         {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}]}
    return glb(doc, blob)


def make(case: str, folder: Path) -> Path:
    """The preset of ``case`` and its file, in ``folder``; returns the preset's path."""
    doc = dict(BASELINE)
    if case.startswith(("hdr", "exr")):
        name = {"hdr-30000x15000": "wide.hdr", "hdr-100000x100000": "huge.hdr", "hdr-negative": "negative.hdr",
                "exr-16384x8192": "big.exr", "exr-8192x4096": "sky.exr", "exr-tiles": "tiles.exr"}[case]
        if case == "hdr-30000x15000":
            (folder / name).write_bytes(hdr(15000, 30000, 93))
        elif case == "hdr-100000x100000":
            (folder / name).write_bytes(hdr(100000, 100000, 95))
        elif case == "hdr-negative":
            (folder / name).write_bytes(hdr(-5, 100, 93))
        elif case == "exr-16384x8192":
            exr(folder / name, 16384, 8192, constant=True)
        elif case == "exr-8192x4096":
            exr(folder / name, 8192, 4096, constant=False)
        else:  # 1 x 1 px, tiles declared 2**25 px wide
            write_tile_bomb(folder / name)
        doc["environment"] = {"world": "file", "file": name, "strength": 1.0}
    else:
        doc = {"schema": "lamp-scene/2", "lamps": [{}], "image": {"width": 8, "height": 8}, "freeform": FREEFORM}
        if case == "glb-250000-nodes":
            data = glb({"asset": {"version": "2.0"}, "nodes": [{"name": f"Empty.{k:06d}"} for k in range(250_000)]})
        elif case == "glb-30MB-empty-chunks":
            data = glb({"asset": {"version": "2.0"}}, extra=struct.pack("<II", 0, 0x12345678) * 3_750_000)
        else:
            data = box_glb(1e103)
        (folder / "lamp.glb").write_bytes(data)
    scene = folder / "scene.json"
    scene.write_text(json.dumps(doc))
    return scene


CASES = ["hdr-30000x15000", "hdr-100000x100000", "hdr-negative", "exr-tiles", "exr-16384x8192", "exr-8192x4096",
         "glb-250000-nodes", "glb-30MB-empty-chunks", "glb-scale-1e103"]


def run(scene: Path, out: Path, cache: Path, size: int) -> tuple[int, float, int, str]:
    """(exit status, wall seconds, peak resident bytes, first line of stderr) of one render."""
    env = dict(os.environ, LAMP_STYLING_CACHE=str(cache))
    command = [sys.executable, "-m", "core_tracer", "render", str(scene), "-o", str(out), "--width", str(size),
               "--height", str(size)]
    with tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        proc = subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        proc.returncode = os.waitstatus_to_exitcode(status)
        err.seek(0)
        said = err.read().decode("utf-8", "replace").strip().splitlines()
    return proc.returncode, wall, usage.ru_maxrss * 1024, said[0] if said else ""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", default="", help="comma-separated cases (default all): " + ", ".join(CASES))
    parser.add_argument("--size", type=int, default=8, help="the render's width and height")
    parser.add_argument("--make", nargs=2, metavar=("CASE", "FOLDER"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.make:
        make(args.make[0], Path(args.make[1]))
        return
    cases = args.only.split(",") if args.only else CASES
    print(f"{'case':<24} {'file':>9} {'exit':>4} {'wall s':>7} {'peak MB':>8}  answer")
    with tempfile.TemporaryDirectory() as tmp:
        for case in cases:
            folder = Path(tmp) / case
            folder.mkdir()
            subprocess.run([sys.executable, __file__, "--make", case, str(folder)], check=True)
            scene = folder / "scene.json"
            files = [p for p in folder.iterdir() if p.name != "scene.json"]
            size = sum(p.stat().st_size for p in files)
            shown = f"{size / 1e6:.1f} MB" if size >= 1e5 else f"{size} B"
            runs = [case, f"{case} (cached)"] if case.startswith("exr-") and case != "exr-tiles" else [case]
            for label in runs:
                code, wall, peak, said = run(scene, folder / "out.exr", folder / "cache", args.size)
                print(f"{label:<24} {shown:>9} {code:>4} {wall:>7.2f} {peak / 2**20:>8.0f}  {said[:110]}", flush=True)


if __name__ == "__main__":
    main()
