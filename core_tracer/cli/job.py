"""A command of the CLI as a worker process: the Blender Measures panel's ``measure``, run off
Blender's main thread.

Started as ``<python> -I -c <bootstrap> <folder holding core_tracer> <command> <its arguments...>``
(``processes.worker_command("cli.job", ...)``), so that inside Blender it imports ``core_tracer``
as a top-level package. It runs exactly what ``python -m core_tracer <command>`` runs; its progress
lines go to stdout, an error to stderr as one line, and SIGTERM (the panel's Esc) ends it leaving no
partial output.
"""

from __future__ import annotations

import sys

from .main import main as cli_main


def main() -> int:
    return cli_main(sys.argv[2:])  # sys.argv[1] is the import root (``processes.worker_command``)
