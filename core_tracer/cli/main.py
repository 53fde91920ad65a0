"""The standalone command line: ``python -m core_tracer <command> ...``.

Each command is a module ``commands/<name>.py`` with a one-line ``HELP``, ``add_arguments(parser)``
and ``run(args) -> int``. Bad user input (a ``SceneError`` or an ``OSError`` on a user's file)
ends with exit status 2 and one line on stderr; Ctrl-C ends with 130 and SIGTERM, handled the
same way, with 143. Outputs are written atomically, so neither leaves a partial file. Anything
else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import signal
import sys
import threading
from collections.abc import Iterator, Sequence

from .. import __version__
from ..scene.reading import SceneError
from ..scene.safe_text import printable
from .common import Terminated

COMMANDS = ("render", "validate", "presets", "study", "optimise", "measure", "states", "relight")

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143  # 128 + SIGTERM, as a shell reports a program ended by it
MAX_ERROR = 2000  # characters of one error line; a hostile file cannot flood the terminal
PROG = "python -m core_tracer"


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage mistake is one line on stderr (exit 2) like every other bad input."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_BAD_INPUT, f"{self.prog}: error: {message}\n")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or, given the ``command`` the arguments start with, of that one
    in full (the others by name only: their modules' imports are a render's fixed cost)."""
    parser = _Parser(prog=PROG, description="The 1990 IPSJ lamp renderer, without Blender.")
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", parser_class=_Parser)
    for name in COMMANDS:
        if command in COMMANDS and name != command:
            sub.add_parser(name)
            continue
        module = importlib.import_module(f".{name}", __package__)
        cmd = sub.add_parser(name, help=module.HELP, description=module.HELP)
        module.add_arguments(cmd)
        cmd.set_defaults(run=module.run)
    return parser


def one_line(text: str) -> str:
    """A message as one printable line: control characters (a file's carriage returns, terminal
    escape sequences) and lone surrogates escaped, the length bounded."""
    return printable(" ".join(str(text).split("\n")), MAX_ERROR)


def raise_terminated(signum, frame) -> None:
    raise Terminated()


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """While the command runs, SIGTERM raises ``Terminated`` wherever the program is, as Ctrl-C
    raises KeyboardInterrupt, instead of ending the process on the spot with its temporary files."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, raise_terminated)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


def _os_error_text(e: OSError) -> str:
    if e.filename is not None and e.strerror:
        return f"{e.filename}: {e.strerror}"
    return str(e)


def main(argv: Sequence[str] | None = None) -> int:
    try:
        with sigterm_as_interrupt():
            try:
                argv = sys.argv[1:] if argv is None else list(argv)
                args = build_parser(argv[0] if argv else None).parse_args(argv)
                return int(args.run(args))
            except SceneError as e:
                print(f"error: {one_line(e)}", file=sys.stderr)
                return EXIT_BAD_INPUT
            except OSError as e:
                print(f"error: {one_line(_os_error_text(e))}", file=sys.stderr)
                return EXIT_BAD_INPUT
    except Terminated:
        print("terminated", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
