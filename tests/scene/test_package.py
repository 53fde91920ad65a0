"""The scene package: its public names, and its modules layered without import circles
(reading and derived below validate)."""

from helpers import ROOT, sibling_imports

import core_tracer.scene as scene
from core_tracer.scene import derived, reading, validate


def test_public_names_are_the_defining_modules_objects():
    defining = {name: module for module in (reading, derived, validate) for name in vars(module)
                if getattr(getattr(module, name), "__module__", None) == module.__name__}
    for name in scene.__all__:
        assert getattr(scene, name) is getattr(defining[name], name), name


def test_reading_and_derived_never_import_validation():
    folder = ROOT / "core_tracer" / "scene"
    assert "validate" not in sibling_imports(folder / "reading.py")
    assert "validate" not in sibling_imports(folder / "derived.py")
    assert {"reading", "derived"} <= sibling_imports(folder / "validate.py")
