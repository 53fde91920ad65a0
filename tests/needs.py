"""What a test needs from the machine, said in one place: a package of ``requirements.txt`` and
Blender's world images (the bpy wheel's). Where one is missing the test skips, saying what is
missing; under CI (``LAMP_REQUIRE_ALL=1``, which ``.ci/run`` sets) it fails instead, so a package
that did not install cannot turn a suite into skips while CI stays green.

Honest skips (no display, no /proc, running as root) stay plain ``pytest.skip``: they say something
about the machine, not about a broken install."""

from __future__ import annotations

import importlib
import os

import pytest

STRICT = os.environ.get("LAMP_REQUIRE_ALL") == "1"


def missing(what: str) -> None:
    """Skip the test for want of ``what`` (a requirement), or fail it under CI."""
    if STRICT:
        pytest.fail(f"{what}: a requirement (requirements.txt), and LAMP_REQUIRE_ALL=1", pytrace=False)
    pytest.skip(what, allow_module_level=True)


def require(module: str, package: str | None = None):
    """``import module`` (its distribution named ``package`` in requirements.txt where that differs),
    or ``missing``; at a module's top it skips or fails the whole module."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        missing(f"{package or module} is not installed ({e})")
