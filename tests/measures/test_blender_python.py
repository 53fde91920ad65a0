"""The extension's workers in an interpreter that has only what a real Blender's Python has (numpy)
plus what the extension bundles (the embreex wheels of blender_manifest.toml, when tools/fetch-wheels
has fetched them): a fresh venv with no packages, numpy 1.26.4 (Blender 4.2–5.0's) linked in.

Before: the Measures panel's worker measured for a minute, then failed drawing the page (matplotlib)
and wrote no folder. Now the measure worker writes its whole folder, and the study worker renders."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from needs import missing

from core_tracer import processes

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def blender_python(tmp_path_factory, repo_root) -> str:
    """The python of a venv whose site-packages holds numpy (and the bundled wheels) only, laid out as
    in a Blender installation: <version>/python/bin/python beside <version>/datafiles (Blender's world
    images, here the bpy wheel's)."""
    bpy_spec = importlib.util.find_spec("bpy")
    if bpy_spec is None:
        missing("the bpy wheel (for Blender's data files) is not installed")
    version = tmp_path_factory.mktemp("blender") / "5.0"
    version.mkdir()
    datafiles = next(Path(bpy_spec.submodule_search_locations[0]).glob("[0-9]*/datafiles"))
    os.symlink(datafiles, version / "datafiles")
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(version / "python")], check=True, timeout=120)
    python = version / "python" / "bin" / "python"
    site = Path(subprocess.run([str(python), "-I", "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    ours = Path(np.__file__).parent.parent
    assert np.__version__ == "1.26.4"  # Blender 4.2–5.0 ship numpy 1.26.x
    for name in ("numpy", "numpy.libs", f"numpy-{np.__version__}.dist-info"):
        if (ours / name).exists():
            os.symlink(ours / name, site / name)
    for wheel in sorted((repo_root / "wheels").glob("*manylinux*.whl")) if sys.platform == "linux" else ():
        with zipfile.ZipFile(wheel) as z:  # what Blender does with a manifest's wheel: unpacked onto the path
            z.extractall(site)
    return str(python)


def _imports(python: str, module: str) -> bool:
    return subprocess.run([python, "-I", "-c", f"import {module}"], capture_output=True, timeout=120).returncode == 0


def test_the_interpreter_has_numpy_and_nothing_blender_lacks(blender_python):
    assert _imports(blender_python, "numpy")
    for module in ("matplotlib", "OpenImageIO", "scipy", "dask", "optuna", "colour", "PIL", "bpy"):
        assert not _imports(blender_python, module), module


def test_the_measure_worker_writes_its_whole_folder(blender_python, repo_root, tmp_path):
    """The Measures panel's command line (``ops.MeasureRun``), beam files on, in that interpreter."""
    out = tmp_path / "stop_measures"
    command = processes.worker_command("cli.job", "measure", str(repo_root / "presets" / "photometric-stop-lamp.json"),
                                       "-o", str(out), "--exit-zero", "--pixel-mm", "4", "--replicates", "1",
                                       "--beam-grid", "30,10,10", python=blender_python)
    proc = subprocess.run(command, capture_output=True, text=True, timeout=1200, env=processes.worker_environment())
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in out.iterdir()) == ["measures.json", "measures.png", "stop.ies", "stop.ldt"]
    assert json.loads((out / "measures.json").read_text(encoding="utf-8"))["verdicts"]
    page = (out / "measures.png").read_bytes()
    assert page.startswith(b"\x89PNG\r\n\x1a\n")
    import OpenImageIO as oiio  # here, in the test's own interpreter: the page is a PNG others read

    buf = oiio.ImageBuf(str(out / "measures.png"))
    assert (buf.spec().width, buf.spec().height) == (1800, 1300)
    pixels = buf.get_pixels(oiio.FLOAT)
    assert pixels.std() > 0.1  # drawn, not blank


def test_the_study_worker_renders(blender_python):
    from helpers import BASELINE

    from core_tracer.scene.reading import read_json
    from core_tracer.study import definition as st
    from core_tracer.study import run as study_run

    study = st.Study.build(read_json(BASELINE), [st.parse_vary("lens.ior=1.4:1.6:2")], (24, 24))
    run = study_run.StudyRun(study, workers=1, python=blender_python)
    run.start()
    try:
        while not run.poll(timeout=0.1):
            pass
    finally:
        run.close()
    assert all(image is not None and image.shape == (24, 24, 3) and image.max() > 0 for image in run.images)
