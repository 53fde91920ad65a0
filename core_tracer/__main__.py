"""``python -m core_tracer``: the standalone command line (see ``cli/main.py``).

A signal from the first moment ends the program as documented (Ctrl-C: 130, SIGTERM: 143, one
line, no traceback), also while the modules are still loading: SIGTERM is caught before anything
else is imported, and an interrupt during the imports is reported here.
"""

import signal
import sys


class _Terminated(KeyboardInterrupt):
    pass


def _terminated(signum, frame) -> None:
    raise _Terminated()


signal.signal(signal.SIGTERM, _terminated)
try:
    from .checkpoints import checkpoint

    checkpoint("start")  # before the modules load (the signal tests stop here)
    from .cli import main as cli
except KeyboardInterrupt as e:
    stopped = isinstance(e, _Terminated)
    print("terminated" if stopped else "interrupted", file=sys.stderr)
    raise SystemExit(143 if stopped else 130) from None
signal.signal(signal.SIGTERM, cli.raise_terminated)  # main() handles it from here
raise SystemExit(cli.main())
