"""Named points in the command line's work where a test can make a signal land, deterministically.

``LAMP_SIGNAL_AT=<name>`` and ``LAMP_SIGNAL_MARKER=<file>`` in the environment: when the work
reaches the point ``<name>``, it creates ``<file>`` and waits (up to ``WAIT`` seconds) until a
SIGINT or SIGTERM arrives, then lets that signal take effect right there, as if it had landed at
that instant. Without these variables a checkpoint costs one dictionary lookup. The signal tests
use it to interrupt renders and studies between any two steps without depending on timing.
"""

from __future__ import annotations

import os
import signal
import threading
import time

ENV_POINT = "LAMP_SIGNAL_AT"
ENV_MARKER = "LAMP_SIGNAL_MARKER"
WAIT = 60.0  # seconds; a test that forgets to signal does not hang the program forever


_passed: set[str] = set()


def checkpoint(name: str) -> None:
    """Reached the point ``name``: wait for the test's signal here if it asked for this point
    (the first time only: a point inside a loop stops the program once)."""
    if os.environ.get(ENV_POINT) != name or name in _passed:
        return
    if threading.current_thread() is not threading.main_thread():
        return
    _passed.add(name)
    marker = os.environ.get(ENV_MARKER)
    caught: list[int] = []
    watched = (signal.SIGINT, signal.SIGTERM)
    previous = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s in watched}
    try:
        if marker:
            with open(marker, "w") as f:
                f.write(name)
        deadline = time.monotonic() + WAIT
        while not caught and time.monotonic() < deadline:
            time.sleep(0.005)  # Python runs signal handlers in the main thread, between these sleeps
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if caught:
        signal.raise_signal(caught[0])  # now handled by whatever the program had installed
