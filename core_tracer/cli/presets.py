"""``presets list|show|validate|thumbnails [FOLDER ...]``: the preset libraries without Blender."""

from __future__ import annotations

import argparse
import json
import os
import sys

from ..library import presets as P
from ..library import shipping
from ..scene.reading import SceneError, scene_to_json

HELP = ("list, show or validate the presets of a library folder (default: the built-in presets), or make "
        "its shipped thumbnails")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    actions = parser.add_subparsers(dest="action", required=True, metavar="ACTION")
    folders_help = "library folders (default: the built-in presets)"
    p = actions.add_parser("list", help="the presets with name, author, tags and file; warnings for bad files")
    p.add_argument("folders", nargs="*", metavar="FOLDER", help=folders_help)
    p.add_argument("--json", action="store_true", help="print the list as JSON")
    p = actions.add_parser("validate", help="check every preset; exit 2 if any file is not a valid preset")
    p.add_argument("folders", nargs="*", metavar="FOLDER", help=folders_help)
    p = actions.add_parser("show", help="print one preset in canonical form")
    p.add_argument("preset", metavar="PRESET", help="preset name, file name or file stem (no folders)")
    p.add_argument("folders", nargs="*", metavar="FOLDER", help=folders_help)
    p = actions.add_parser("thumbnails", help=f"make the thumbnails shipped in FOLDER/{P.SHIPPED_THUMBNAIL_FOLDER}/ "
                           "for every preset and remove stale ones (run after editing a preset)")
    p.add_argument("folders", nargs="*", metavar="FOLDER", help=folders_help)
    p.add_argument("--check", action="store_true",
                   help="change nothing; exit 2 if a thumbnail is missing or stale")
    for sub in actions.choices.values():
        sub.error = parser.error  # one-line usage errors, as the parent parser


def _libraries(folders: list[str]) -> list[P.Library]:
    if not folders:
        return [P.builtin_library()]
    libraries = []
    for folder in folders:
        if not os.path.isdir(folder):
            raise SceneError(folder, "is not a folder; a library is a folder of *.json presets")
        libraries.append(P.Library(os.path.basename(os.path.normpath(folder)) or folder, folder,
                                   writable=os.access(folder, os.W_OK)))
    return libraries


def _print_warnings(warnings: list[P.PresetWarning]) -> None:
    for w in warnings:
        print(f"warning: {w}", file=sys.stderr)


def _thumbnails(libraries: list[P.Library], check: bool) -> int:
    status = 0
    for library in libraries:
        if check:
            state = shipping.check_shipped_thumbnails(library)
            for line in state.problems():
                print(f"problem: {line}", file=sys.stderr)
            if not state.ok:
                again = "" if library.folder == P.BUILTIN_FOLDER else f" {library.folder}"
                print(f"{library.folder}: the shipped thumbnails are out of date; run {P.REGENERATE_COMMAND}{again}",
                      file=sys.stderr)
                status = 2
            continue
        made, removed, warnings = shipping.make_shipped_thumbnails(library)
        for path in made:
            print(f"made: {P.printable(path)}")
        for path in removed:
            print(f"removed: {P.printable(path)}")
        _print_warnings(warnings)
        status = 2 if warnings else status
    return status


def run(args: argparse.Namespace) -> int:
    libraries = _libraries(args.folders)
    if args.action == "thumbnails":
        return _thumbnails(libraries, args.check)
    entries, warnings = P.list_presets(libraries)
    if args.action == "list":
        if args.json:
            rows = [{"name": e.name, "author": e.author, "tags": list(e.tags), "description": e.description,
                     "file": e.file, "library": e.library.name} for e in entries]
            print(json.dumps(rows, indent=2, ensure_ascii=False))
        else:
            width = max((len(P.printable(e.name, 60)) for e in entries), default=0)
            for e in entries:
                tags = ", ".join(e.tags)
                author = f" by {P.printable(e.author, 60)}" if e.author else ""
                print(f"{P.printable(e.name, 60):<{width}}  [{P.printable(tags, 80)}]{author}  "
                      f"({P.printable(e.library.name, 60)}: {P.printable(os.path.basename(e.file))})")
        _print_warnings(warnings)
        return 0
    if args.action == "validate":
        for e in entries:
            print(f"ok: {P.printable(e.file)}")
        _print_warnings(warnings)
        print(f"{len(entries)} valid, {len(warnings)} not valid", file=sys.stderr)
        return 2 if warnings else 0
    # show
    if os.path.basename(args.preset) != args.preset or "/" in args.preset or "\\" in args.preset:
        raise SceneError(args.preset, "a preset is named without folders; give the folder as FOLDER")
    entry = P.find_preset(entries, args.preset)
    if entry is None:
        names = ", ".join(sorted(P.printable(e.name, 60) for e in entries)) or "none"
        raise SceneError(args.preset, f"no such preset in {', '.join(lib.folder for lib in libraries)}; "
                                      f"the valid presets are: {names}")
    sys.stdout.write(scene_to_json(entry.scene))
    return 0
