"""Files a document names beside itself: a free-form design's .glb (``freeform.mesh_file``) and a
preset's environment image (``environment.file``).

A shared preset must not reach outside its library: such a file is a plain file name (no folder, no
hidden file), looked up in the document's own folder (never the working directory), and refused
when a link leads out of that folder. The checks stat the file but never read it.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Sequence

from .reading import SceneError
from .safe_text import printable

ENVIRONMENT_SUFFIXES = (".exr", ".hdr")
FAR_FIELD_SUFFIXES = (".ies", ".ldt")  # an LED's far-field file (spec.FAR_FIELD_SUFFIXES)


def check_plain_name(name: str, suffixes: Sequence[str], where: str) -> None:
    """A plain file name ending in one of ``suffixes``: no folder, no hidden file."""
    bad = (not name or name != name.strip() or "/" in name or "\\" in name or name.startswith(".")
           or "\0" in name or ":" in name or not name.lower().endswith(tuple(suffixes))
           or any(name.lower() == suffix for suffix in suffixes))
    if bad:
        raise SceneError(where, f'"{printable(name, 60)}" is not allowed; allowed a plain file name ending in '
                                f"{' or '.join(suffixes)} beside the document, without folders")


def path_beside(document: str | os.PathLike, name: str, where: str, kind: str, missing: str) -> tuple[str, int]:
    """(path, size) of the file ``name`` beside ``document``, a regular file in its folder after
    following links; ``kind`` says what is allowed ("a .glb"), ``missing`` what to do when it is not
    there. Checks the name first (``check_plain_name`` is the caller's)."""
    folder = os.path.dirname(os.path.abspath(os.fspath(document)))
    path = os.path.join(folder, name)
    shown = printable(name, 60)
    if os.path.dirname(os.path.realpath(path)) != os.path.realpath(folder):
        raise SceneError(where, f'"{shown}" leads outside the design\'s folder; allowed a file beside the JSON')
    try:
        st = os.stat(path)
    except OSError:
        raise SceneError(where, f'"{shown}" is missing; allowed {kind} beside the JSON{missing}') from None
    if not stat.S_ISREG(st.st_mode):
        raise SceneError(where, f'"{shown}" is not a regular file; allowed {kind} file')
    return path, st.st_size


def environment_file(document: str | os.PathLike, env: dict) -> str | None:
    """The environment image a document's normalised ``environment`` section names, confined to the
    document's folder (None for none or one of Blender's bundled worlds, found by name). A missing
    file, a path with folders (absolute or with ``..``) and a link out of the folder are refused
    with one line; a user's own image elsewhere is given on the command line (``--environment``)
    or chosen in Blender."""
    if env.get("world") != "file":
        return None
    name = env.get("file", "")
    where = "environment.file"
    if name and os.path.isabs(os.path.expanduser(name)) and not os.path.exists(os.path.expanduser(name)):
        raise SceneError(where, f"{printable(name, 200)!r} does not exist; allowed an existing .exr or .hdr file "
                                "beside the document")
    try:
        check_plain_name(name, ENVIRONMENT_SUFFIXES, where)
    except SceneError as e:
        raise SceneError(where, f"{e.message} (a user's own image elsewhere: render --environment PATH, or "
                                "choose it in Blender)") from None
    return path_beside(document, name, where, "an .exr or .hdr", "")[0]


SECTIONS = ("lamps", "freeform")  # where a scene names curves: its lamps, its free-form parts


def named_curves(scene: dict, sections: tuple[str, ...] = SECTIONS) -> list[tuple[tuple, str]]:
    """The measured curves a normalised photometric scene reads, as (where the name sits: a key path
    into the scene, the JSON path shown in messages): a bulb's ``spectrum_file``, a lens's or prism
    plate's ``filter_file``, an LED section's ``spectrum_file`` and ``far_field_file``, the same of
    free-form bulbs and lenses (none in the paper mode); of
    the lamps, the free-form parts or both (``sections``)."""
    if scene.get("light_model") != "photometric":
        return []
    named: list[tuple[tuple, str]] = []
    for i, lamp in enumerate(scene["lamps"] if "lamps" in sections else ()):
        parts = [("bulb", lamp["bulb"]), ("lens", lamp["lens"])]
        if lamp.get("collection", "reflector") == "prism_plate":
            parts.append(("prism_plate", lamp["prism_plate"]))
        if lamp.get("source", "bulb") == "led":  # its dies' spectrum and far field
            parts.append(("led", lamp["led"]))
        named += [(("lamps", i, name, key), f"lamps[{i}].{name}.{key}") for name, part in parts
                  for key in _curve_keys(part)]
    for i, part in enumerate(scene.get("freeform", {}).get("parts", ()) if "freeform" in sections else ()):
        role = part["role"]
        named += [(("freeform", "parts", i, role, key), f"freeform.parts[{i}].{role}.{key}")
                  for key in _curve_keys(part[role])]
    return named


def _curve_keys(section: dict) -> list[str]:
    """The curve files a bulb, lens or plate section reads: its spectrum or filter given by file."""
    keys = []
    if section.get("type", "custom") == "custom" and section.get("spectrum") == "file":
        keys.append("spectrum_file")
    if section.get("filter") == "file":
        keys.append("filter_file")
    if section.get("distribution") == "file":  # an LED's far-field file
        keys.append("far_field_file")
    return keys


def spectrum_files(document: str | os.PathLike, scene: dict, sections: tuple[str, ...] = SECTIONS
                   ) -> dict[tuple, str]:
    """The measured curves (.csv) a normalised photometric scene names beside ``document``, by key
    path (``named_curves``); each confined to the document's folder as ``environment_file`` is."""
    found: dict[tuple, str] = {}
    for keys, where in named_curves(scene, sections):
        name = _at(scene, keys)
        suffixes = FAR_FIELD_SUFFIXES if keys[-1] == "far_field_file" else (".csv",)
        check_plain_name(name, suffixes, where)
        found[keys] = path_beside(document, name, where, " or ".join(suffixes), "")[0]
    return found


def _at(scene: dict, keys: tuple):
    node = scene
    for key in keys:
        node = node[key]
    return node


def with_curves_at(scene: dict, paths: dict[tuple, str]) -> dict:
    """``scene`` with the file names at ``paths``' key paths replaced by their values (full paths);
    the sections on the way copied, the rest shared."""
    if not paths:
        return scene
    out = dict(scene)
    for keys, path in paths.items():
        node = out
        for key in keys[:-1]:
            child = node[key]
            child = list(child) if isinstance(child, list) else dict(child)
            node[key] = child
            node = child
        node[keys[-1]] = path
    return out


def with_spectrum_files(document: str | os.PathLike, scene: dict, sections: tuple[str, ...] = SECTIONS) -> dict:
    """``scene`` with the measured curves it names (``spectrum_files``; of ``sections``) by their full
    paths, to be traced whatever the working directory (the scene itself, when it names none)."""
    return with_curves_at(scene, spectrum_files(document, scene, sections))
