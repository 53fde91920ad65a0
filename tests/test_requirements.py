"""Every package pinned in requirements.txt is installed at its pinned version: a package that failed
to install fails here, by name, rather than turning the suites that need it into skips
(``tests/needs.py``; under CI those fail too)."""

from __future__ import annotations

import importlib.metadata
import re

import pytest
from helpers import ROOT

PINNED = [tuple(line.split("==")) for line in (ROOT / "requirements.txt").read_text(encoding="utf-8").splitlines()
          if line.strip() and not line.startswith("#")]


def test_every_requirement_is_pinned():
    assert len(PINNED) > 10
    for pin in PINNED:
        assert len(pin) == 2 and re.fullmatch(r"[A-Za-z0-9_.-]+", pin[0]) and pin[1], pin


@pytest.mark.parametrize(("name", "version"), PINNED, ids=[name for name, _ in PINNED])
def test_installed_at_the_pinned_version(name, version):
    try:
        installed = importlib.metadata.version(name)
    except importlib.metadata.PackageNotFoundError:
        pytest.fail(f"{name} {version} (requirements.txt) is not installed: tools/ensure-venv", pytrace=False)
    assert installed == version, f"{name}: {installed} installed, {version} pinned"


def test_ci_turns_a_missing_requirement_into_a_failure():
    assert "\nexport LAMP_REQUIRE_ALL=1\n" in (ROOT / ".ci" / "run").read_text(encoding="utf-8")
