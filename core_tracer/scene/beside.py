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


def spectrum_files(document: str | os.PathLike, scene: dict) -> dict[tuple[int, str, str], str]:
    """The measured curves (.csv) a normalised photometric scene names beside ``document``, by (lamp,
    section, key): a bulb's ``spectrum_file``, a lens's or prism plate's ``filter_file``, an LED
    section's ``spectrum_file`` and ``far_field_file``; each
    confined to the document's folder as ``environment_file`` is (none in the paper mode)."""
    found: dict[tuple[int, str, str], str] = {}
    if scene.get("light_model") != "photometric":
        return found
    for i, lamp in enumerate(scene["lamps"]):
        named = []
        if lamp["bulb"]["type"] == "custom" and lamp["bulb"]["spectrum"] == "file":
            named.append(("bulb", "spectrum_file"))
        if lamp["lens"]["filter"] == "file":
            named.append(("lens", "filter_file"))
        if lamp.get("collection", "reflector") == "prism_plate" and lamp["prism_plate"]["filter"] == "file":
            named.append(("prism_plate", "filter_file"))
        if lamp.get("source", "bulb") == "led":
            named += led_files(lamp["led"])
        for section, key in named:
            where = f"lamps[{i}].{section}.{key}"
            name = lamp[section][key]
            suffixes = FAR_FIELD_SUFFIXES if key == "far_field_file" else (".csv",)
            check_plain_name(name, suffixes, where)
            found[(i, section, key)] = path_beside(document, name, where, " or ".join(suffixes), "")[0]
    return found


def led_files(led: dict) -> list[tuple[str, str]]:
    """(section, key) of the files an LED section reads: its spectrum and its far field."""
    named = []
    if led["spectrum"] == "file":
        named.append(("led", "spectrum_file"))
    if led["distribution"] == "file":
        named.append(("led", "far_field_file"))
    return named


def with_spectrum_files(document: str | os.PathLike, scene: dict) -> dict:
    """``scene`` with the measured curves it names (``spectrum_files``) by their full paths, to be
    traced whatever the working directory (the scene itself, when it names none)."""
    found = spectrum_files(document, scene)
    if not found:
        return scene
    lamps = [dict(lamp) for lamp in scene["lamps"]]
    for (i, section, key), path in found.items():
        lamps[i][section] = {**lamps[i][section], key: path}
    return {**scene, "lamps": lamps}
