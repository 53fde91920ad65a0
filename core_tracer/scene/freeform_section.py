"""The ``freeform`` section of a ``lamp-scene/2`` document: reading it, and what it means for hashes.

The generic reader checks each field against ``spec.FREEFORM``; the rules here are the ones the
declarations cannot say: a part names its mesh and its role, gives values only under its role's
key, names each mesh once, and the mesh file is a plain ``.glb`` name beside the document (never a
folder: a shared preset must not reach outside its library).
"""

from __future__ import annotations

from typing import Any

from . import spec as S
from .beside import check_plain_name
from .derived import section_defaults, without_defaults
from .reading import SceneError
from .safe_text import printable

MESH_SUFFIX = ".glb"


def check_mesh_file_name(name: str, where: str = "freeform.mesh_file") -> None:
    """A plain ``*.glb`` file name, no folder, no hidden file: the mesh file lies beside the JSON."""
    check_plain_name(name, (MESH_SUFFIX,), where)


def finish_freeform(raw: Any, section: dict) -> dict:
    """The normalised freeform section from ``section`` (checked against ``spec.FREEFORM`` by the
    generic reader) and the raw document's ``raw`` (to tell a given key from a default)."""
    check_mesh_file_name(section["mesh_file"])
    seen: dict[str, int] = {}
    parts = []
    for i, (given, part) in enumerate(zip(raw["parts"], section["parts"], strict=True)):
        where = f"freeform.parts[{i}]"
        if "object" not in given or not part["object"]:
            raise SceneError(f"{where}.object", "is required; allowed the name of a mesh in the mesh file")
        name = part["object"]
        if name in seen:
            raise SceneError(f"{where}.object", f'"{printable(name, 40)}" is already given in '
                                                f"freeform.parts[{seen[name]}]; allowed each mesh once")
        seen[name] = i
        if "role" not in given:
            raise SceneError(f"{where}.role", f"is required; allowed {S.FREEFORM_PART.fields['role'].range_text()}")
        role = part["role"]
        stray = next((r for r in S.FREEFORM_ROLES if r != role and r in given), None)
        if stray is not None:
            raise SceneError(f"{where}.{stray}", f'is not a value of role "{role}"; allowed only the key "{role}"')
        values = part.get(role)
        if values is None:
            values = section_defaults(S.FREEFORM_ROLE_SECTIONS[role])
        parts.append({"object": name, "role": role, role: values})
    return {"mesh_file": section["mesh_file"], "parts": parts}


def freeform_without_defaults(section: dict) -> dict:
    """The freeform section with every role value at its default left out (for hashes)."""
    parts = []
    for part in section["parts"]:
        role = part["role"]
        values = without_defaults(part[role], S.FREEFORM_ROLE_SECTIONS[role])
        parts.append({"object": part["object"], "role": role, **({role: values} if values else {})})
    return {"mesh_file": section["mesh_file"], "parts": parts}
