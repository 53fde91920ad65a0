"""A band worker process: traces bands of the renders a ``band_pool`` sends it.

Started by ``band_pool`` as ``<python> -I -c <bootstrap> <folder holding core_tracer> <flag file>``,
so it imports ``core_tracer`` as a top-level package whatever name the parent knows it by (inside
Blender the parent's copy is ``bl_ext.<repo>.lamp_styling.core_tracer``). Everything that crosses
the pipes is therefore made of builtins and numpy arrays, never of core_tracer's classes.

Protocol: pickles, each after its length (8 bytes, little-endian), over stdin and stdout.

- parent to worker: ``("render", serial, scene, width, height, options)`` starts a render
  (``options``: the keywords of ``engine.make_context`` and ``keep_passes``); ``("job", job)``
  answers a take, ``job`` being (index, y0, y1) or None for no more. End of input: exit.
- worker to parent: ``("ready", pid)`` once, then per render ``("take", serial)`` for each band it
  wants, ``("band", serial, index, image, passes, segments, busy, max_depth, transitions, pid, cut_at_depth)`` as each
  band completes, ``("error", serial, text)`` if the render failed, and ``("idle", serial)`` last.

The flag file's first 4 bytes hold the serial of the render the parent wants traced; once they
differ from its render's, the worker stops within a generation and reports idle. Anything else the
process prints goes to stderr.
"""

from __future__ import annotations

import mmap
import os
import pickle
import signal
import struct
import sys
import traceback

from .engine.render import make_context
from .engine.schedule import BandImage, worker_bands

_LENGTH = struct.Struct("<Q")
_SERIAL = struct.Struct("<I")


def read_message(stream):
    """The next message on ``stream``, None at the end of it."""
    head = stream.read(_LENGTH.size)
    if len(head) < _LENGTH.size:
        return None
    (size,) = _LENGTH.unpack(head)
    body = stream.read(size)
    if len(body) < size:
        return None
    return pickle.loads(body)


def write_message(stream, message) -> None:
    body = pickle.dumps(message, protocol=pickle.HIGHEST_PROTOCOL)
    stream.write(_LENGTH.pack(len(body)))
    stream.write(body)
    stream.flush()


def main() -> int:
    # The parent owns cancellation: Ctrl-C in a terminal reaches the whole process group, and the
    # parent stops the render itself, so the workers ignore it rather than print tracebacks.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "SIGPIPE"):  # the parent killed: end quietly at the next message, as a pipeline does
        signal.signal(signal.SIGPIPE, signal.SIG_DFL)
    inbox = os.fdopen(os.dup(sys.stdin.fileno()), "rb")
    outbox = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # stray prints must not corrupt the protocol

    with open(sys.argv[2], "rb") as flag_file:
        flag = mmap.mmap(flag_file.fileno(), _SERIAL.size, access=mmap.ACCESS_READ)
    write_message(outbox, ("ready", os.getpid()))
    while (message := read_message(inbox)) is not None:
        if message[0] != "render":
            continue  # an answer to a take of a render already ended
        _, serial, scene, width, height, options = message

        def stopped(serial: int = serial) -> bool:
            return _SERIAL.unpack_from(flag)[0] != serial

        def take(serial: int = serial) -> tuple[int, int, int] | None:
            if stopped():
                return None
            write_message(outbox, ("take", serial))
            answer = read_message(inbox)
            if answer is None:
                raise SystemExit(0)  # the parent is gone
            return answer[1]

        options = dict(options)
        keep_passes = options.pop("keep_passes")
        try:
            ctx = make_context(scene, width, height, **options)
            for index, band in worker_bands(ctx, take, stopped):
                rows = BandImage.of(band, keep_passes)
                write_message(outbox, ("band", serial, index, rows.image, rows.passes, rows.segments, rows.busy,
                                       rows.max_depth, rows.transitions, os.getpid(), rows.cut_at_depth))
        except SystemExit:
            raise
        except BaseException:  # reported to the parent, which raises it in the render's thread
            write_message(outbox, ("error", serial, traceback.format_exc()))
        write_message(outbox, ("idle", serial))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
