"""``python -m core_tracer --version``: the one version the extension and the package carry. Its
source is ``core_tracer.__version__``; the manifest, pyproject.toml and the CHANGELOG's latest release
repeat it."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from core_tracer import __version__


@pytest.mark.slow
def test_version_is_printed(repo_root):
    proc = subprocess.run([sys.executable, "-m", "core_tracer", "--version"], cwd=repo_root, capture_output=True,
                          text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == f"python -m core_tracer {__version__}"


def test_version_is_the_manifests_and_the_packages(repo_root):
    for name in ("blender_manifest.toml", "pyproject.toml"):
        text = (repo_root / name).read_text(encoding="utf-8")
        assert re.search(r'^version = "([^"]+)"', text, re.M).group(1) == __version__, name


def test_the_changelogs_latest_release_is_the_version(repo_root):
    text = (repo_root / "CHANGELOG.md").read_text(encoding="utf-8")
    releases = re.findall(r"^## \[(\d+\.\d+\.\d+)\]", text, re.M)
    assert releases and releases[0] == __version__, releases
