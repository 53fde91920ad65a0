"""How fast is the viewport preview? For a region of 1024x768 on 2 threads, the time from a restart
(a design edit or a view change) to the coarse image, to the full-resolution image and to the
refined one (16 samples per pixel, adaptive), through the engine's own stages
(``lamp_addon.render.preview``), for the four-lamp preset seen two ways: through the preset's own
camera (the lamp fills the view) and from a three-quarter viewport view.

    .venv/bin/python benchmarks/bench_viewport.py [--runs 5] [--threads 2] [--size 1024x768]

Targets of the viewport preview: first image <= 0.1 s; full resolution <= 0.4 s. Also prints the time of each
candidate coarse divisor, the figure the coarse stage's divisor is chosen from, and the CPU time of the
full-resolution render on one thread: on a machine shared with other work the steadier figure, to
compare versions by.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

import core_tracer  # noqa: E402


def _addon_package():
    """The extension as Blender loads it (its root ``__init__`` is a package holding ``lamp_addon``
    and ``core_tracer`` side by side); nothing of it needs ``bpy`` until ``register``."""
    spec = importlib.util.spec_from_file_location("lamp_styling", ROOT / "__init__.py",
                                                  submodule_search_locations=[str(ROOT)])
    package = importlib.util.module_from_spec(spec)
    sys.modules["lamp_styling"] = package
    spec.loader.exec_module(package)
    from lamp_styling.lamp_addon.convert import viewport  # type: ignore[import-not-found]
    from lamp_styling.lamp_addon.render import preview as render_preview  # type: ignore[import-not-found]

    return render_preview, viewport


def _look_at_view(eye, centre) -> list[list[float]]:
    """A viewport's view matrix (world to view) looking from ``eye`` at ``centre``, Z up."""
    eye, centre = np.asarray(eye, float), np.asarray(centre, float)
    back = eye - centre
    back /= np.linalg.norm(back)
    right = np.cross([0.0, 0.0, 1.0], back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    rotation = np.array([right, up, back])
    view = np.eye(4)
    view[:3, :3] = rotation
    view[:3, 3] = -rotation @ eye
    return view.tolist()


def _perspective_window(width: int, height: int, lens_mm: float = 50.0, sensor_mm: float = 36.0,
                        near: float = 0.01, far: float = 100.0) -> list[list[float]]:
    """Blender's viewport projection for a lens (the sensor spans the region's larger side)."""
    half = sensor_mm / (2.0 * lens_mm)
    half_w, half_h = (half, half * height / width) if width >= height else (half * width / height, half)
    window = np.zeros((4, 4))
    window[0, 0], window[1, 1] = 1.0 / half_w, 1.0 / half_h
    window[2, 2], window[2, 3] = -(far + near) / (far - near), -2.0 * far * near / (far - near)
    window[3, 2] = -1.0
    return window.tolist()


def cpu_seconds(pool) -> float:
    """CPU time of this process and of the band pool's worker processes (Linux: /proc; elsewhere
    this process only)."""
    total = time.process_time()
    for pid in pool.process_ids() if pool is not None else ():
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        total += (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime + stime
    return total


def _time_stages(render_preview, scene: dict, width: int, height: int, threads: int, runs: int, pool):
    """Per stage, over the runs, the minimum and the median of the time from the restart to its
    image, and the minimum CPU time (all threads and worker processes) to it."""
    walls, cpus = [], []
    for _ in range(runs):
        preview = render_preview.ProgressivePreview(threads=threads)
        start, cpu_start = time.perf_counter(), cpu_seconds(pool)
        preview.restart(scene, width, height)
        run_walls, run_cpus = [], []
        while preview.step():
            run_walls.append(time.perf_counter() - start)
            run_cpus.append(cpu_seconds(pool) - cpu_start)
        walls.append(run_walls)
        cpus.append(run_cpus)
    per_stage = zip(zip(*walls, strict=True), zip(*cpus, strict=True), strict=True)
    return [(min(w), statistics.median(w), min(c)) for w, c in per_stage]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", default=str(ROOT / "presets" / "four-lamp-rear-combination.json"))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--size", default="1024x768")
    parser.add_argument("--no-pool", action="store_true",
                        help="bands on threads of this process instead of the band pool's worker processes")
    args = parser.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    render_preview, viewport = _addon_package()
    band_pool = render_preview.band_pool  # the add-on's copy, the one its preview uses
    band_pool.enabled = not args.no_pool
    pool = band_pool.shared()
    if pool is not None and not pool.ready(30):
        raise SystemExit(f"the band pool did not start: {pool.broken}")

    design = core_tracer.load_scene(args.preset)
    core_tracer.render(design, 64, 48)  # warm up imports and caches
    views = {
        "preset camera": design["camera"],
        "three-quarter view": viewport.camera_from_view(
            width, height, _perspective_window(width, height),
            _look_at_view((-0.38, -0.62, 0.22), (0.0, 0.04, 0.0))),
    }
    print(f"preset        {Path(args.preset).name}")
    print(f"machine       {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}; "
          f"{args.threads} threads, {args.runs} runs; bands in "
          + (f"{pool.size} worker processes (started before timing, as after a first render)" if pool
             else "threads of this process"))
    print(f"region        {width}x{height}; stages 1/{render_preview.coarse_divisor(width, height)}, full, then "
          f"{render_preview.REFINE_SAMPLES} samples per pixel (targets: first <= 0.1 s, full <= 0.4 s); "
          "times from the restart, min / median (CPU min)")
    for name, camera in views.items():
        scene = {**design, "camera": camera, "image": {"width": width, "height": height}}
        stages = _time_stages(render_preview, scene, width, height, args.threads, args.runs, pool)
        print(f"{name:<20} " + "   ".join(f"{label} {w:.3f} / {m:.3f} s (CPU {c:.3f} s)" for label, (w, m, c)
                                        in zip(("first image", "full resolution", "refined"), stages, strict=False)))
        for divisor in (2, 4, 8, 16):
            w, h = render_preview.stage_size(width, height, divisor)
            times = []
            for _ in range(args.runs):
                start = time.perf_counter()
                core_tracer.render_passes(scene, w, h, threads=args.threads, keep_passes=False, pool=pool)
                times.append(time.perf_counter() - start)
            print(f"{'':<20} 1/{divisor:<2} ({w}x{h}) {min(times):.3f} / {statistics.median(times):.3f} s")
        cpus = []
        for _ in range(args.runs):
            start = time.process_time()
            core_tracer.render_passes(scene, width, height, threads=1, keep_passes=False)
            cpus.append(time.process_time() - start)
        print(f"{'':<20} full resolution on 1 thread: CPU {min(cpus):.3f} / {statistics.median(cpus):.3f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
