"""Shared by the preset tests with and without Blender: a folder of hostile presets, and
designs flattened to compare them parameter for parameter."""

from __future__ import annotations

import json
import os
from pathlib import Path

from helpers import PRESETS

BUILTIN = PRESETS


def _doc(stem: str = "paper-baseline") -> dict:
    return json.loads((BUILTIN / f"{stem}.json").read_text())


def make_hostile_folder(folder: Path) -> tuple[set[str], dict[str, tuple[str, ...]]]:
    """Good presets and bad ones; returns the good file names and, per bad file, what its warning says."""
    folder.mkdir()
    base = _doc()
    (folder / "good-1.json").write_text(json.dumps(base))
    (folder / "good-2.json").write_text(json.dumps(_doc("four-lamp-rear-combination")))
    os.symlink("good-1.json", folder / "link-inside.json")  # a link within the library is fine
    bad: dict[str, tuple[str, ...]] = {}

    def write(name: str, content: str | bytes, *needles: str) -> None:
        data = content.encode() if isinstance(content, str) else content
        (folder / name).write_bytes(data)
        bad[name] = needles

    with open(folder / "huge.json", "wb") as f:
        f.truncate(100 * 1024 * 1024)  # 100 MB, sparse
    bad["huge.json"] = ("104857600 bytes", "at most 1000000 bytes")
    write("many-lamps.json", '{"schema": "lamp-scene/1", "lamps": [' + ",".join(["{}"] * 300_000) + "]}",
          "lamps: has 300000 items; allowed 1 to 4")
    write("huge-image.json", json.dumps({**base, "image": {"width": 100_000, "height": 100_000}}),
          "image.width: 100000 is out of range; allowed [1, 8192] px")
    write("deep.json", "[" * 100_000 + "]" * 100_000, "nested too deeply")
    write("deep-name.json", '{"schema": "lamp-scene/1", "name": ' + "[" * 5000 + "]" * 5000 + "}",
          "nested too deeply")
    write("not-utf8.json", b'{"name": "\xff\xfe\xfa"}', "not UTF-8")
    write("future.json", json.dumps({**base, "schema": "lamp-scene/3"}), "schema:", '"lamp-scene/3" is not supported')
    write("not-json.json", "{{", "not valid JSON")
    write("empty.json", "", "not valid JSON")
    write("unknown-key.json", json.dumps({**base, "bulb_power": 3}), "bulb_power: unknown key")
    write("nan.json", json.dumps(base).replace('"ior": 1.49', '"ior": NaN'), "NaN")
    write("range.json", json.dumps(base).replace('"ior": 1.49', '"ior": 0.5'),
          "lamps[0].lens.ior: 0.5 is out of range; allowed [1, 3]")
    text = json.dumps(base)
    for name, number, shown in (("big-int.json", "9" * 5000, "a number of 5000 digits"),
                                ("int-310.json", "9" * 310, "a number of 310 digits"),
                                ("int-4300.json", "-" + "9" * 4300, "a number of 4300 digits"),
                                ("float-400.json", "9" * 400 + ".5", "a number of 401 digits"),
                                ("exponent.json", "1e400", "1e400")):
        write(name, text.replace('"ior": 1.49', '"ior": ' + number), f"lamps[0].lens.ior: {shown} is out of range")
    write("huge-width.json", text.replace('"width": 512', '"width": ' + "1" * 400),
          "image.width: a number of 400 digits is out of range; allowed [1, 8192] px")
    surrogate = "lone surrogate"
    write("surrogate-name.json", text.replace('"name": "', '"name": "\\ud800'), "name:", surrogate)
    write("surrogate-description.json", json.dumps({**base, "description": "a \udfff b"}), "description:",
          surrogate)
    write("surrogate-tag.json", json.dumps({**base, "tags": ["red", "\udbff"]}), "tags[1]:", surrogate)
    write("repeated-key.json", text.replace('"ior": 1.49', '"ior": 99, "ior": 1.49'),
          "lamps[0].lens.ior: is given twice in one object")
    write("escape-key.json", json.dumps({**base, "x\x1b[2J\ry": 1}), "x\\x1b[2J\\ry: unknown key")
    write("huge-key.json", '{"schema": "lamp-scene/1", "' + "k" * 900_000 + '": 1}', "unknown key")
    write("array.json", "[1, 2, 3]", "JSON object")
    write("line\nbreak.json", "nope", "not valid JSON")
    os.mkfifo(folder / "fifo.json")  # opening it would block forever
    bad["fifo.json"] = ("not a regular file",)
    (folder / "dir.json").mkdir()
    bad["dir.json"] = ("not a regular file",)
    (folder.parent / "outside.json").write_text(json.dumps(base))
    os.symlink("../outside.json", folder / "escape.json")
    bad["escape.json"] = ("leads out of the library",)
    os.symlink("/dev/zero", folder / "zero.json")
    bad["zero.json"] = ("leads out of the library",)
    os.symlink("loop.json", folder / "loop.json")
    bad["loop.json"] = ("cannot read",)
    # Free-form presets whose mesh file is not plain data beside them.
    mesh_lamp = {**base, "schema": "lamp-scene/2",
                 "freeform": {"mesh_file": "x.glb", "parts": [{"object": "Lens", "role": "lens"}]}}

    def with_mesh_file(name: str) -> str:
        return json.dumps({**mesh_lamp, "freeform": {**mesh_lamp["freeform"], "mesh_file": name}})

    write("mesh-folder.json", with_mesh_file("../outside.glb"), "freeform.mesh_file", "without folders")
    write("mesh-missing.json", with_mesh_file("gone.glb"), "freeform.mesh_file", "is missing")
    (folder.parent / "outside.glb").write_bytes(b"glTF")
    os.symlink("../outside.glb", folder / "escape.glb")
    write("mesh-escape.json", with_mesh_file("escape.glb"), "freeform.mesh_file", "leads outside")
    (folder / "notes.txt").write_text("not a preset, not listed")
    os.symlink("..", folder / "thumbnails")  # a thumbnail folder leading out: neither listed nor opened
    (folder / ".hidden.json").write_text("hidden, not listed")
    os.mkdir(folder / "sub")
    (folder / "sub" / "nested.json").write_text(json.dumps(base))  # only the folder itself is a library
    return {"good-1.json", "good-2.json", "link-inside.json"}, bad
