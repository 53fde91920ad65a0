"""A study's worker process: renders the variants it is sent, one at a time.

Started by ``study_run`` as ``<python> -I -c <bootstrap> <folder holding core_tracer>``, so it
imports ``core_tracer`` as a top-level package whatever name the parent knows it by (inside
Blender the parent's copy is ``bl_ext.<repo>.lamp_styling.core_tracer``).

Protocol, one JSON object per line:

- stdin, a job: ``{"index": i, "scene": {...}, "width": w, "height": h, "threads": t, "out": path}``;
  end of input means no more work;
- stdout: ``{"index": i, "progress": f}`` now and then,
  ``{"index": i, "done": true, "seconds": s}`` when the image is in ``out`` (a ``.npy`` file,
  renamed into place when complete), or ``{"index": i, "error": "..."}``.

Anything else the process prints goes to stderr, which the parent keeps in a log file.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time

PROGRESS_INTERVAL = 0.2  # seconds between progress messages of one render


def main() -> int:
    # The parent owns cancellation: Ctrl-C in a terminal reaches the whole process group, and the
    # parent then stops the workers itself, so they ignore it rather than print tracebacks.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "SIGPIPE"):  # the parent killed: end quietly at the next message, as a pipeline does
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    protocol = os.fdopen(os.dup(sys.stdout.fileno()), "w", buffering=1, encoding="utf-8")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())

    # imported once stdout is the protocol's own copy: whatever an import prints goes to stderr
    import numpy as np

    from ..freeform.traced import render_scene
    from ..images import glare
    from ..raytrace.engine import RenderCancelled

    parent = os.getppid()

    def send(message: dict) -> None:
        protocol.write(json.dumps(message) + "\n")

    def orphaned() -> bool:
        return os.getppid() != parent  # the parent died: stop instead of rendering for nobody

    for line in sys.stdin:
        if not line.strip():
            continue
        job = json.loads(line)
        index = job["index"]
        last = [0.0]

        def progress(fraction: float, index: int = index, last: list = last) -> None:
            now = time.monotonic()
            if now - last[0] >= PROGRESS_INTERVAL:
                last[0] = now
                send({"index": index, "progress": round(fraction, 4)})

        start = time.perf_counter()
        try:
            result = render_scene(job["scene"], job["width"], job["height"], progress=progress,
                                   should_stop=orphaned, threads=job.get("threads", 1), keep_passes=False)
            partial = job["out"] + ".part.npy"
            np.save(partial, glare.apply(result.image, job["scene"]))
            os.replace(partial, job["out"])
        except RenderCancelled:
            return 1
        except Exception as e:  # reported to the parent, which stops the study with this message
            send({"index": index, "error": f"{type(e).__name__}: {e}"})
            continue
        send({"index": index, "done": True, "seconds": round(time.perf_counter() - start, 4)})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
