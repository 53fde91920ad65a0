"""The third hardening campaign kept as tests (issue 33 item 6): generated hostile light-states files
(read and relit), cache cells, optimise files, study and scheduler flags, and spectra, each
classified as refused in one line, accepted with finite output, a traceback, a hang or a
non-finite output; only the first two are allowed.

The default run is short (``SMALL`` inputs a surface). ``LAMP_FUZZ_EXAMPLES=N`` multiplies it, as in
tests/scene/test_fuzz_inputs.py; ``python tests/test_fuzz_round3.py N`` runs a campaign of N inputs a
surface and prints the counts."""

from __future__ import annotations

import collections
import os
import random
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import helpers
import hostile_files as H
import numpy as np
import pytest
from helpers import BASELINE, FUZZ_SCALE, ROOT, cli_command

from core_tracer.scene.reading import SceneError

SMALL = 12
CLI_TIMEOUT = 120  # seconds before a command counts as hung
BAD = ("traceback", "hang", "non-finite")


def _cli(args: list, folder: Path, env: dict | None = None, timeout: float = CLI_TIMEOUT) -> tuple[str, str]:
    """(outcome, detail) of one command run in ``folder`` (a relative path it is given lands there, never
    in the work tree): refused, accepted, traceback or hang."""
    env = dict(os.environ, PYTHONPATH=str(ROOT), **(env or {}))
    try:
        done = subprocess.run(cli_command(*args), cwd=folder, capture_output=True, text=True, timeout=timeout,
                              env=env, errors="replace")
    except subprocess.TimeoutExpired:
        return "hang", " ".join(map(str, args))[:200]
    lines = done.stderr.splitlines()
    if "Traceback" in done.stderr or done.returncode not in (0, 2) or (done.returncode == 2 and len(lines) != 1):
        return "traceback", done.stderr[-400:]
    return ("accepted" if done.returncode == 0 else "refused"), lines[0] if lines else ""


# ---------------------------------------------------------------------------------------------
# The surfaces: each runs ``n`` generated inputs and counts their outcomes


def states_files(n: int, folder: Path, rng: random.Random, cli_every: int = 6) -> collections.Counter:
    """Hostile light-states files read in this process; every ``cli_every``-th relit by the command too."""
    from core_tracer.images.imageio import read_image
    from core_tracer.measures import states as S
    from core_tracer.scene.validate import parse_scene

    doc = helpers.baseline_doc()
    doc["image"].update(width=24, height=16, samples=1)
    good = S.to_bytes(S.render_states(parse_scene(doc)))
    out: collections.Counter = collections.Counter()
    for i in range(n):
        kind, data = H.hostile_states_file(rng, good)
        start = time.monotonic()
        try:
            light = S.from_bytes(data, "f.npz")
            arrays = [light.surroundings, *light.passes.values()]
            out["accepted" if all(np.isfinite(a).all() for a in arrays) else "non-finite"] += 1
        except SceneError:
            out["refused"] += 1
        except Exception as e:  # noqa: BLE001 (counted: the campaign's finding)
            out["traceback"] += 1
            out[f"traceback {kind}: {type(e).__name__}: {str(e)[:80]}"] += 1
        if time.monotonic() - start > 5:
            out["hang"] += 1
        if i % cli_every == 0:
            path = folder / f"states{i}.npz"
            path.write_bytes(data)
            image = folder / f"relit{i}.exr"
            outcome, detail = _cli(["relight", path, "-o", image, "--level", "surroundings=" + rng.choice(
                ["1", "100000", "0"])], folder)
            out[f"relight {outcome}"] += 1
            if outcome == "accepted" and not np.isfinite(read_image(image)[0]).all():
                out["non-finite"] += 1
            if outcome in BAD:
                out[outcome] += 1
                out[f"relight {kind}: {detail}"] += 1
    return out


def cache_cells(n: int, folder: Path, rng: random.Random) -> collections.Counter:
    """Hostile files where a cell is kept: each dropped (and reported) or a finite image of its size."""
    import contextlib
    import io

    from core_tracer.cluster.cache import CellCache

    good = np.linspace(0, 1, 6 * 8 * 3, dtype=np.float32).reshape(6, 8, 3)
    out: collections.Counter = collections.Counter()
    for i in range(n):
        cache = CellCache(folder / f"cache{i}")
        key = f"{i:064x}"
        path = Path(cache.path(key))
        path.parent.mkdir(parents=True, exist_ok=True)
        kind, data = H.hostile_cell(rng, good)
        if data == "fifo":
            os.mkfifo(path)
        elif data == "folder":
            path.mkdir()
        elif data == "link":
            os.symlink("/dev/zero", path)
        else:
            path.write_bytes(data)
        start = time.monotonic()
        said = io.StringIO()
        try:
            with contextlib.redirect_stderr(said):
                image = cache.get(key, (8, 6))
            if image is None:
                ok = said.getvalue().count("\n") == 1 and "rendering it again" in said.getvalue()
                out["refused" if ok and not os.path.lexists(path) else "traceback"] += 1
            else:
                out["accepted" if image.shape == good.shape and np.isfinite(image).all() else "non-finite"] += 1
        except Exception as e:  # noqa: BLE001
            out["traceback"] += 1
            out[f"traceback {kind}: {type(e).__name__}: {str(e)[:80]}"] += 1
        if time.monotonic() - start > 5:
            out["hang"] += 1
    return out


def optimise_files(n: int, folder: Path, rng: random.Random) -> collections.Counter:
    """Hostile optimise files: read (``spec.from_doc``) and, when accepted, their study opened; nothing
    may appear outside their folder."""
    from core_tracer.optimise import spec, storage

    good = {"schema": spec.SCHEMA, "base": "base.json",
            "parameters": [{"parameter": "cuts.height", "range": [0.5, 2.0]}],
            "objectives": [{"measure": "lens_luminance", "goal": "maximise"}], "size": [12, 12], "trials": 2}
    outside = set(os.listdir(folder.parent))
    out: collections.Counter = collections.Counter()
    for i in range(n):
        place = folder / f"opt{i}"
        place.mkdir()
        (place / "base.json").write_text(BASELINE.read_text())
        kind, doc = H.hostile_optimise_doc(rng, good)
        try:
            opt = spec.from_doc(doc, str(place), "o")
            storage.open_study(opt)
            out["accepted"] += 1
        except SceneError:
            out["refused"] += 1
        except Exception as e:  # noqa: BLE001
            out["traceback"] += 1
            out[f"traceback {kind}: {type(e).__name__}: {str(e)[:80]}"] += 1
    if set(os.listdir(folder.parent)) != outside:
        out["touched outside"] += 1
    return out


def study_flags(n: int, folder: Path, rng: random.Random) -> collections.Counter:
    """Hostile ``study`` flags and scheduler addresses, through the command."""
    out: collections.Counter = collections.Counter()
    tree = _listing(ROOT)
    for i in range(n):
        kind, args, env = H.hostile_study_flags(rng)
        env = {"DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT": "2s", "LAMP_STYLING_CACHE": str(folder / "cache"), **env}
        outcome, detail = _cli(["study", BASELINE, "--vary", "lens.ior=1.4,1.6", "--size", "16x16", *args, "-o",
                                folder / f"s{i}.png"], folder, env)
        out[outcome] += 1
        if outcome in BAD:
            out[f"{outcome} {kind} {[a[:60] for a in args]}: {detail[-120:]}"] += 1
    if _listing(ROOT) != tree:
        out["touched outside"] += 1
    return out


def _listing(root: Path) -> set[str]:
    """The work tree's top-level names (what a command given a relative folder would add to)."""
    return set(os.listdir(root))


def spectra(n: int, folder: Path, rng: random.Random) -> collections.Counter:
    """Hostile bulbs and measured curves: refused when loaded, or rendered finite."""
    out: collections.Counter = collections.Counter()
    for i in range(n):
        place = folder / f"sp{i}"
        place.mkdir()
        what = rng.choice(["bulb", "filter", "spectrum"])
        if what == "bulb":
            kind, fields = H.hostile_bulb(rng)
            path = H.spectrum_scene_file(place, bulb=fields)
        else:
            kind, text = H.hostile_curve(rng)
            path = H.spectrum_scene_file(place, **({"lens_curve": text} if what == "filter" else {"bulb_curve": text}))
        try:
            out["accepted" if H.refused_or_renders(path) == "rendered" else "refused"] += 1
        except AssertionError:
            out["non-finite"] += 1
            out[f"non-finite {what} {kind}"] += 1
        except Exception as e:  # noqa: BLE001
            out["traceback"] += 1
            out[f"traceback {what} {kind}: {type(e).__name__}: {str(e)[:80]}"] += 1
    return out


SURFACES = {"states files -> relight": states_files, "cache cells": cache_cells, "optimise files": optimise_files,
            "study and scheduler flags": study_flags, "spectra and curves": spectra}


def _clean(counts: collections.Counter) -> None:
    bad = {k: v for k, v in counts.items() if k.split(" ")[0] in BAD or k == "touched outside"}
    assert not bad, bad


@pytest.mark.slow
@pytest.mark.parametrize("surface", [s for s in SURFACES if s != "study and scheduler flags"])
def test_a_campaign_finds_no_traceback_hang_or_non_finite_output(tmp_path, surface):
    counts = SURFACES[surface](SMALL * FUZZ_SCALE, tmp_path, random.Random(33))
    _clean(counts)
    assert counts["refused"] > 0, counts


@pytest.mark.slow
def test_study_and_scheduler_flags_find_no_traceback_or_hang(tmp_path):
    counts = study_flags(SMALL // 2 * FUZZ_SCALE, tmp_path, random.Random(33))
    _clean(counts)


if __name__ == "__main__":  # python tests/test_fuzz_round3.py N [SURFACE...]: N inputs a surface
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    chosen = [s for s in SURFACES if not sys.argv[2:] or any(a in s for a in sys.argv[2:])]
    print("| surface | inputs | refused | accepted | tracebacks | hangs | non-finite | seconds |")
    print("|---|---|---|---|---|---|---|---|")
    for name in chosen:
        run = SURFACES[name]
        start = time.monotonic()
        with tempfile.TemporaryDirectory() as tmp:
            work = Path(tmp) / "f"
            work.mkdir()
            got = run(count // 3 if name == "study and scheduler flags" else count, work, random.Random(2026))
        inputs = sum(v for k, v in got.items() if k in ("refused", "accepted", "traceback", "non-finite"))
        print(f"| {name} | {inputs} | {got['refused']} | {got['accepted']} | {got['traceback']} | {got['hang']} | "
              f"{got['non-finite']} | {time.monotonic() - start:.0f} |", flush=True)
        for key, value in sorted(got.items()):
            if key.split(" ")[0] in BAD or key.startswith(("relight", "touched")):
                print(f"    {key}: {value}", flush=True)
