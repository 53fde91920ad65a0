"""Preset libraries: folders of ``lamp-scene/1`` JSON files, listed, saved and shared safely.

A preset is data, never code: a JSON file validated by ``scene.parse_scene`` with the same
rules and messages as the CLI. A *library* is one folder: the built-in presets (read-only),
a designer's own folder, a team share. Listing a folder never fails as a whole: every file
that is not a valid preset becomes a warning naming the file and the field, and the others
still show. Hostile files are bounded: a file is refused by its size before it is read
(``scene.MAX_FILE_BYTES``), a list of lamps by its length before its items are looked at, and
nothing but regular ``*.json`` files directly in the folder is opened; a link that leads out of
the library is skipped. Writes are atomic (``fileio``), so a crash never leaves half a preset.

Thumbnails are small tracer renders as PNG whose file name carries a hash of the preset's
canonical JSON, so a changed preset gets a new thumbnail. A library may ship them in its
``thumbnails/`` folder (the built-in presets do: ``python -m core_tracer presets thumbnails``
makes them, ``shipping``); otherwise they are made on demand and cached beside the presets (``.thumbnails/``)
when the library is writable, else in a cache folder.
"""

from __future__ import annotations

import copy
import hashlib
import os
import unicodedata
from dataclasses import dataclass, field

from .. import fileio
from ..freeform.loading import mesh_file_path
from ..images import display
from ..images.display import ViewTransform
from ..scene.beside import environment_file, with_spectrum_files
from ..scene.derived import without_defaults
from ..scene.freeform_section import freeform_without_defaults
from ..scene.reading import SceneError, read_json, scene_to_json
from ..scene.safe_text import printable
from ..scene.validate import normalize, parse_scene

SUFFIX = ".json"
THUMBNAIL_FOLDER = ".thumbnails"  # made on demand beside the presets of a writable library
SHIPPED_THUMBNAIL_FOLDER = "thumbnails"  # made on purpose and shipped with the library
REGENERATE_COMMAND = "python -m core_tracer presets thumbnails"
MAX_THUMBNAIL_BYTES = 1_000_000  # a 96 x 96 PNG is a few kB; anything bigger is not ours
THUMBNAIL_SIZE = 96
MAX_SLUG = 64
MAX_MESSAGE = 400  # a warning quotes the file; a hostile key or value must not flood the list
BUILTIN_FOLDER = os.path.join(fileio.EXTENSION_ROOT, "presets")
_RESERVED = {"con", "prn", "aux", "nul", *(f"com{i}" for i in range(10)), *(f"lpt{i}" for i in range(10))}


class PresetError(SceneError):
    """A preset operation that cannot be done; ``str()`` names the file or library."""


class PresetExistsError(PresetError):
    """Saving would replace an existing preset and ``overwrite`` was not given."""


@dataclass(frozen=True)
class Library:
    """A folder of presets. ``writable`` says whether this program may save, rename and delete there."""

    name: str
    folder: str
    writable: bool


@dataclass(frozen=True)
class PresetEntry:
    """One valid preset found in a library."""

    name: str
    author: str
    tags: tuple[str, ...]
    description: str
    file: str
    library: Library
    digest: str  # hash of the canonical JSON of the normalised scene
    scene: dict = field(repr=False, compare=False)


@dataclass(frozen=True)
class PresetWarning:
    """A file in a library that is not a usable preset; ``message`` names the field."""

    file: str
    library: Library
    message: str

    def __str__(self) -> str:
        return f"{self.file}: {self.message}" if self.file else self.message


def builtin_library() -> Library:
    """The presets shipped with the program (read-only)."""
    return Library("Built-in", BUILTIN_FOLDER, writable=False)


# ---------------------------------------------------------------------------------------------
# Names and paths


def slug(name: str) -> str:
    """A safe file stem for a preset name: lower case letters and digits joined by '-'."""
    text = unicodedata.normalize("NFKC", name).casefold()
    parts: list[str] = []
    word = ""
    for ch in text:
        if ch.isalnum():
            word += ch
        elif word:
            parts.append(word)
            word = ""
    if word:
        parts.append(word)
    stem = "-".join(parts)[:MAX_SLUG].strip("-") or "preset"
    if stem in _RESERVED:
        stem += "-preset"
    return stem


def preset_file(library: Library, file_name: str) -> str:
    """The path of ``file_name`` in ``library``; refuses anything that is not a plain ``*.json`` name."""
    bad = (not file_name or file_name != os.path.basename(file_name) or "/" in file_name or "\\" in file_name
           or file_name.startswith(".") or not file_name.lower().endswith(SUFFIX) or "\0" in file_name)
    if bad:
        raise PresetError(printable(file_name), f"not a preset file name; allowed a plain name ending in {SUFFIX} "
                          "inside the library, without folders")
    return os.path.join(library.folder, file_name)


def _inside(library: Library, path: str) -> bool:
    """Whether ``path`` (after following links) is a file directly in the library's folder."""
    real_folder = os.path.realpath(library.folder)
    return os.path.dirname(os.path.realpath(path)) == real_folder


# ---------------------------------------------------------------------------------------------
# Reading


def _parse(path: str) -> dict:
    """Validate a preset file; the error's ``path`` is the field ('' for the file as a whole)."""
    try:
        doc = read_json(path)
    except SceneError as e:  # named by the file; a repeated key also by its field
        field = e.path[len(path) + 2:] if e.path.startswith(path + ": ") else ""
        raise SceneError(field, e.message) from None
    scene = parse_scene(doc)
    if "freeform" in scene:
        _check_mesh_file(path, scene)
    environment_file(path, scene["environment"])  # an image beside the preset, or refused
    return scene


def load_preset(path: str | os.PathLike) -> dict:
    """Read and validate one preset file; a ``SceneError`` names the file and the field."""
    name = os.fspath(path)
    try:
        return _parse(name)
    except SceneError as e:
        raise SceneError(f"{name}: {e.path}" if e.path else name, e.message) from None


def digest(scene: dict) -> str:
    """The hash of a normalised scene that names its thumbnail. Fields at their defaults are left
    out, so a field added to the spec with a default leaves every existing hash as it was."""
    parametric = {key: value for key, value in scene.items() if key != "freeform"}
    design = without_defaults(parametric)
    if "freeform" in scene:
        design["freeform"] = freeform_without_defaults(scene["freeform"])
    else:
        # A design without free-form parts is the lamp-scene/1 document it migrated from: hashed as
        # that, so every thumbnail made before lamp-scene/2 keeps its name.
        design["schema"] = "lamp-scene/1"
    return hashlib.sha256(scene_to_json(design).encode("utf-8")).hexdigest()[:16]


def _entry(library: Library, path: str, scene: dict) -> PresetEntry:
    return PresetEntry(name=scene["name"], author=scene["author"], tags=tuple(scene["tags"]),
                       description=scene["description"], file=path, library=library, digest=digest(scene),
                       scene=scene)


def list_library(library: Library) -> tuple[list[PresetEntry], list[PresetWarning]]:
    """Every preset of one library, sorted by file name, and a warning for every file that is not one."""
    entries: list[PresetEntry] = []
    warnings: list[PresetWarning] = []
    folder = library.folder
    try:
        names = sorted(os.listdir(folder))
    except OSError as e:
        warnings.append(PresetWarning(printable(folder), library,
                                      f"cannot open the library \"{printable(library.name)}\" "
                                      f"({e.strerror or e})"))
        return entries, warnings
    for file_name in names:
        if file_name.startswith(".") or not file_name.lower().endswith(SUFFIX):
            continue
        path = os.path.join(folder, file_name)
        shown = printable(path)
        if not _inside(library, path):
            warnings.append(PresetWarning(shown, library, "is a link that leads out of the library; skipped"))
            continue
        try:
            scene = _parse(path)
        except SceneError as e:
            field = f"{printable(e.path, 120)}: " if e.path else ""
            warnings.append(PresetWarning(shown, library, field + printable(e.message)))
            continue
        entries.append(_entry(library, path, scene))
    return entries, warnings


def _check_mesh_file(path: str, scene: dict) -> None:
    """A free-form preset's mesh file is data from whoever shared the library: a plain .glb name
    beside the preset, not leading out of the library, within the size limit. Its contents are
    read and checked (triangle limits, closed lenses) only when the preset is used."""
    try:
        mesh_file_path(path, scene["freeform"]["mesh_file"])
    except SceneError as e:
        raise SceneError("freeform.mesh_file", e.message) from None


def list_presets(libraries: list[Library] | tuple[Library, ...]) -> tuple[list[PresetEntry], list[PresetWarning]]:
    """The presets of several libraries, in library order, and the warnings of all of them."""
    entries: list[PresetEntry] = []
    warnings: list[PresetWarning] = []
    for library in libraries:
        e, w = list_library(library)
        entries += e
        warnings += w
    return entries, warnings


def find_preset(entries: list[PresetEntry], key: str) -> PresetEntry | None:
    """The entry whose file name, file stem or preset name is ``key`` (case-insensitive)."""
    k = key.casefold()
    for entry in entries:
        base = os.path.basename(entry.file)
        if k in (base.casefold(), os.path.splitext(base)[0].casefold(), entry.name.casefold()):
            return entry
    return None


# ---------------------------------------------------------------------------------------------
# Writing


def _require_writable(library: Library) -> None:
    if not library.writable:
        raise PresetError(printable(library.folder), f"the library \"{printable(library.name)}\" is read-only")


def save_preset(library: Library, name: str, scene: dict, *, overwrite: bool = False) -> PresetEntry:
    """Save ``scene`` under ``name`` as ``<slug>.json`` in ``library``; returns its entry.

    The scene is validated first (nothing is written if it is invalid) and saved in canonical
    form with ``name`` as its name. An existing file is replaced only with ``overwrite=True``,
    otherwise ``PresetExistsError`` names it, even when another process saves the same name at
    the same moment. The write is atomic: the old file stays intact until the new one is complete.
    """
    _require_writable(library)
    doc = copy.deepcopy(scene)
    if isinstance(doc, dict):
        doc["name"] = name
    checked = normalize(doc)
    path = preset_file(library, slug(name) + SUFFIX)
    if not os.path.isdir(library.folder):
        raise PresetError(printable(library.folder), f"the library \"{printable(library.name)}\" folder does not exist")
    exists = PresetExistsError(printable(path), "a preset with this file name exists already; "
                               "confirm to replace it (overwrite=True)")
    if os.path.lexists(path) and not overwrite:
        raise exists
    try:
        # Without overwrite the name is taken atomically: of two designers saving the same new
        # name at the same moment, exactly one succeeds and the other is told it is taken.
        fileio.atomic_write_text(path, scene_to_json(checked), overwrite=overwrite)
    except fileio.TargetExistsError:
        raise exists from None
    return _entry(library, path, checked)


def _own_file(entry: PresetEntry) -> str:
    _require_writable(entry.library)
    path = preset_file(entry.library, os.path.basename(entry.file))
    if os.path.normpath(path) != os.path.normpath(entry.file) or not _inside(entry.library, path):
        raise PresetError(printable(entry.file), f"is not a file of the library \"{printable(entry.library.name)}\"")
    return path


def delete_preset(entry: PresetEntry) -> None:
    """Remove a preset (and its cached thumbnails) from a writable library."""
    path = _own_file(entry)
    os.unlink(path)
    _forget_thumbnails(entry.library, path)


def rename_preset(entry: PresetEntry, new_name: str, *, overwrite: bool = False) -> PresetEntry:
    """Give a preset a new name (and the file the matching slug) in its writable library."""
    old = _own_file(entry)
    scene = load_preset(old)
    new = save_preset(entry.library, new_name, scene, overwrite=overwrite or preset_file(
        entry.library, slug(new_name) + SUFFIX) == old)
    if os.path.normpath(new.file) != os.path.normpath(old):
        os.unlink(old)
        _forget_thumbnails(entry.library, old)
    return new


# ---------------------------------------------------------------------------------------------
# Thumbnails


# How a thumbnail shows its preset. It is part of the thumbnail's name, so a change to the display
# pipeline makes every thumbnail stale (``presets thumbnails --check`` says so) instead of leaving
# old-looking ones in place.
THUMBNAIL_LOOK = (f"{display.DEFAULT_VIEW}; auto exposure {display.AUTO_TARGET:g} at the "
                  f"{display.AUTO_PERCENTILE:g}th percentile within {display.AUTO_REGION_STOPS:g} stops of the "
                  f"{display.AUTO_BRIGHT_END:g}th")


# How a photometric preset's thumbnail shows it instead: at its own camera (``images.photometric``).
PHOTOMETRIC_THUMBNAIL_LOOK = (f"{display.DEFAULT_VIEW}; XYZ in cd/m2 to linear Rec.709 at the camera's EV100 "
                              f"(its ev100, or auto exposure {display.AUTO_TARGET:g} as an EV100)")


def thumbnail_digest(entry: PresetEntry) -> str:
    """The hash of a preset's content and of how it is shown (``THUMBNAIL_LOOK``, or
    ``PHOTOMETRIC_THUMBNAIL_LOOK`` for a photometric preset)."""
    look = THUMBNAIL_LOOK
    if entry.scene.get("light_model") == "photometric":
        from ..raytrace import spectral_bands  # loaded for a photometric preset only

        look = f"{PHOTOMETRIC_THUMBNAIL_LOOK}; {spectral_bands.look(with_spectrum_files(entry.file, entry.scene))}"
    return hashlib.sha256(f"{entry.digest}\n{look}".encode()).hexdigest()[:16]


def thumbnail_name(entry: PresetEntry) -> str:
    """``<file stem>-<hash of the preset and of how it is shown>.png``: the same in every thumbnail folder."""
    stem = os.path.splitext(os.path.basename(entry.file))[0]
    return f"{stem}-{thumbnail_digest(entry)}.png"


def own_subfolder(library: Library, subfolder: str) -> str | None:
    """``<library>/<subfolder>``, unless it is a link that leads out of the library."""
    folder = os.path.join(library.folder, subfolder)
    inside = os.path.dirname(os.path.realpath(folder)) == os.path.realpath(library.folder)
    return folder if inside else None


def _thumbnail_in(entry: PresetEntry, subfolder: str) -> str | None:
    """The thumbnail of ``entry`` in ``<library>/<subfolder>/`` if it is there and looks like one.

    Only a regular file of a thumbnail's size whose real location is that folder counts: a link
    out of the library is never opened, whoever wrote the library."""
    folder = own_subfolder(entry.library, subfolder)
    if folder is None:
        return None
    path = os.path.join(folder, thumbnail_name(entry))
    try:
        ok = os.path.isfile(path) and os.path.getsize(path) <= MAX_THUMBNAIL_BYTES
    except OSError:
        return None
    return path if ok and os.path.dirname(os.path.realpath(path)) == os.path.realpath(folder) else None


def shipped_thumbnail(entry: PresetEntry) -> str | None:
    """The thumbnail shipped with the library (``thumbnails/``) for the preset as it is now, if any."""
    return _thumbnail_in(entry, SHIPPED_THUMBNAIL_FOLDER)


def thumbnail_path(entry: PresetEntry, cache_dir: str | os.PathLike) -> str:
    """Where the thumbnail of ``entry`` is, or is to be made.

    First the library's shipped ``thumbnails/`` folder, if it holds the thumbnail of the preset's
    current content; else ``<library>/.thumbnails/`` when the library is writable; else, for a
    read-only library, ``.thumbnails/`` if someone who may write there made it already, or
    ``cache_dir``. The name carries the hash of the preset's canonical JSON, so an edited preset
    misses every stale thumbnail and gets a fresh one.
    """
    shipped = shipped_thumbnail(entry)
    if shipped is not None:
        return shipped
    beside = own_subfolder(entry.library, THUMBNAIL_FOLDER)
    made = _thumbnail_in(entry, THUMBNAIL_FOLDER)
    if beside is not None and entry.library.writable and os.access(entry.library.folder, os.W_OK):
        path = os.path.join(beside, thumbnail_name(entry))
        # Made here (or to be made here); anything else under that name (a link out of the
        # library, a huge file, a folder) is neither opened nor replaced: the cache is used.
        if made == path or not os.path.lexists(path):
            return path
        return os.path.join(os.fspath(cache_dir), thumbnail_name(entry))
    return made if made is not None else os.path.join(os.fspath(cache_dir), thumbnail_name(entry))


def _is_thumbnail_of(name: str, stem: str) -> bool:
    key = name[len(stem) + 1:-4]
    return name.startswith(stem + "-") and name.endswith(".png") and len(key) == 16 and key.isalnum()


def _remove_thumbnails(folder: str, stem: str, keep: str = "") -> None:
    try:
        names = os.listdir(folder)
    except OSError:
        return
    for name in names:
        old = os.path.join(folder, name)
        if _is_thumbnail_of(name, stem) and old != keep:
            try:
                os.unlink(old)
            except OSError:
                pass


def _forget_thumbnails(library: Library, preset_path: str) -> None:
    """Remove the thumbnails of a preset file that is gone from its (writable) library."""
    stem = os.path.splitext(os.path.basename(preset_path))[0]
    for subfolder in (THUMBNAIL_FOLDER, SHIPPED_THUMBNAIL_FOLDER):
        folder = own_subfolder(library, subfolder)
        if folder is not None:
            _remove_thumbnails(folder, stem)


def make_thumbnail(entry: PresetEntry, path: str | os.PathLike, size: int = THUMBNAIL_SIZE, *,
                   view: ViewTransform | None = None) -> str:
    """Render ``entry`` with the tracer at ``size`` x ``size`` and write it as PNG (atomically), shown
    as everywhere else: through ``view`` (default Blender's AgX, ``images.display``) at the design's
    automatic exposure; a photometric design at its camera's EV100 (``images.photometric``), so that
    thumbnails of designs under one EV100 compare."""
    from .. import render  # the tracer loads only when a thumbnail is actually made
    from ..images.imageio import write_image

    target = os.fspath(path)
    scene = copy.deepcopy(entry.scene)
    scene["image"] = {"width": int(size), "height": int(size)}
    image_file = environment_file(entry.file, scene["environment"])  # beside the preset, by its full path
    traced = scene if image_file is None else {**scene, "environment": {**scene["environment"], "file": image_file}}
    traced = with_spectrum_files(entry.file, traced)  # the measured curves beside the preset, by their full paths
    if "freeform" in scene:  # the meshes are read and checked now, before they are used
        from ..freeform import render_passes as render_freeform  # free-form only: loads Embree
        from ..freeform.loading import load_meshes

        image = render_freeform(traced, load_meshes(entry.file, scene), size, size).image
    else:
        image = render(traced, size, size)
    from ..images import glare

    image = glare.apply(image, scene)  # the design's glare, as the CLI and Blender show it
    os.makedirs(os.path.dirname(os.path.abspath(target)), exist_ok=True)
    from ..images import display, photometric

    # the paper mode at its automatic exposure, the photometric one at its own camera (display.shown)
    shown = display.shown(image, scene, view=None)
    used = shown.exposure
    write_image(target, shown.pixels[0], scene, view=view, exposure=used.paper_stops or 0.0,
                attributes={photometric.EV100_ATTRIBUTE: f"{used.ev100:g}"} if used.ev100 is not None else None)
    stem = os.path.splitext(os.path.basename(entry.file))[0]
    _remove_thumbnails(os.path.dirname(os.path.abspath(target)), stem, keep=os.path.abspath(target))
    return target
