# SPDX-License-Identifier: GPL-3.0-or-later
"""A design's free-form parts written for the worker processes (a study's, Measure Design's), as the
command line has them: a document naming a ``.glb`` beside it.

The design as F12 renders it gets a ``freeform`` section (``freeform.scene``) naming its mesh file by
a plain name, as an exported pair does (``with_parts``): a study's JSON (on the sheet image, in a
saved sheet's header) is a ``lamp-study/1`` document the command line re-runs with the ``.glb``
beside it. Blender's glTF exporter writes the meshes once per run (``export.write_glb``, the parts
and the parametric lamps traced with them, in the design root's frame) into this session's folder,
under a name made of their bytes' SHA-256 (``lamp-study-<hash>.glb``: the same meshes, the same
name; a changed design, a new one). What a worker traces names that file by its full path
(``traced``, ``runnable``), found in that folder and confined to it like every file a document names
(``core_tracer.freeform.loading.mesh_file_path``); a Dask worker is sent its bytes
(``cluster.cells``), the ``measure`` worker finds it beside its scene file (``measures.ops``). Save
Sheet copies the file beside the sheet (``copy_beside``), where ``study --study sheet.png`` looks.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import os
import shutil
import tempfile

import bpy

from ...core_tracer import fileio
from ...core_tracer.scene.beside import with_curves_at
from ...core_tracer.scene.reading import SceneError
from ...core_tracer.study import definition as st
from ..design import curves as design_curves
from . import export as freeform_export
from . import geometry as freeform_geometry
from . import parametric as freeform_parametric
from . import scene as freeform_scene
from . import status as freeform_status

MESH_FILE = ("freeform", "mesh_file")
_folder: list[str] = []  # this session's folder of study meshes (made on first use)


def folder() -> str:
    """This session's folder of the written mesh files."""
    if not _folder:
        _folder.append(tempfile.mkdtemp(prefix="lamp_study_meshes_"))
    return _folder[0]


def shown_parts(bl_scene) -> list:
    """The free-form parts the scene renders (none: the study is of the parametric design)."""
    return freeform_geometry.parts_in(bpy.context.evaluated_depsgraph_get()) if bl_scene is not None else []


def with_parts(bl_scene, base: dict, parts: list) -> dict:
    """``base`` (the design seen as each cell sees it) with the ``freeform`` section of ``parts`` and
    the parametric lamps traced with them; their meshes written now to this session's folder under
    the name of their contents. Raises ``SceneError`` naming the part or the reason (no Embree)."""
    ok, reason = freeform_status.available()
    if not ok:
        raise SceneError("Free-form Parts", f"cannot be studied: {reason}")
    built = freeform_parametric.built_parts(bl_scene, bpy.context.evaluated_depsgraph_get())
    handle, path = tempfile.mkstemp(suffix=".glb", prefix=".writing-", dir=folder())  # a study and a measure at once
    os.close(handle)
    try:
        freeform_export.write_glb(bl_scene, parts, path, built)
        with open(path, "rb") as f:
            name = f"lamp-study-{hashlib.sha256(f.read()).hexdigest()[:16]}.glb"
        os.replace(path, os.path.join(folder(), name))
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(path)
        raise
    try:
        scene = freeform_scene.with_freeform(base, parts, name, freeform_parametric.part_documents(built, base))
    except SceneError as e:
        raise SceneError("free-form part", freeform_status.part_error_text(e, parts)) from None
    # photometric: the parts' measured curves by their full paths (beside the .blend or the preset)
    return design_curves.with_curves(bl_scene, scene, ("freeform",))


def mesh_path(scene: dict) -> str | None:
    """The full path of the mesh file ``scene`` names in this session's folder (None for a parametric
    design); confined to that folder (``core_tracer.freeform.loading.mesh_file_path``). Raises
    ``SceneError`` when the file is not there (a study of an earlier session)."""
    if "freeform" not in scene:
        return None
    from ...core_tracer.freeform.loading import mesh_file_path

    return mesh_file_path(os.path.join(folder(), "design.json"), scene["freeform"]["mesh_file"])


def traced(scene: dict) -> dict:
    """``scene`` (``with_parts``'s) naming its mesh file by its full path; a parametric one as it is."""
    path = mesh_path(scene)
    return scene if path is None else with_curves_at(scene, {MESH_FILE: path})


def runnable(study: st.Study) -> st.Study:
    """The study whose variants name the mesh file by its full path, their geometry checked once
    before any worker starts; the study itself when it has no meshes."""
    if "freeform" not in study.base:
        return study
    from ...core_tracer.freeform.traced import meshes_of

    variants = tuple(dataclasses.replace(v, scene=traced(v.scene)) for v in study.variants)
    first = variants[0].scene
    design = meshes_of(first)
    design.cache.get(first, design.meshes)  # an open lens, overlapping lenses: one line, before the workers
    return dataclasses.replace(study, variants=variants)


def copy_beside(study: st.Study, sheet_path: str) -> str | None:
    """Copy the study's mesh file beside the sheet saved at ``sheet_path`` (kept when a file of that
    name, hence those bytes, is there already); its path, or None for a parametric study. Raises
    ``SceneError`` when the file is no longer in this session's folder."""
    try:
        source = mesh_path(study.base)
    except SceneError:
        raise SceneError("Save Sheet", "the study's meshes are gone (a study of an earlier session); allowed: run "
                                       "the study again, then save its sheet") from None
    if source is None:
        return None
    target = os.path.join(os.path.dirname(os.path.abspath(sheet_path)), os.path.basename(source))
    if not os.path.exists(target):
        with fileio.atomic_path(target, overwrite=False) as tmp:
            shutil.copyfile(source, tmp)
    return target


def register() -> None:
    pass  # the folder is made on first use


def unregister() -> None:
    if _folder:
        shutil.rmtree(_folder.pop(), ignore_errors=True)
