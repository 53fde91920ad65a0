"""The Blender Measures panel's worker process: the ``measure`` command, run off Blender's main thread.

Started as ``<python> -I -c <bootstrap> <folder holding core_tracer> <measure's arguments...>``
(``processes.worker_command``), so that inside Blender it imports ``core_tracer`` as a top-level
package. It runs exactly what ``python -m core_tracer measure`` runs; its progress lines go to
stdout, an error to stderr as one line, and SIGTERM (the panel's Esc) ends it leaving no partial
output.
"""

from __future__ import annotations

import sys


def main() -> int:
    from ..cli.main import main as cli_main

    return cli_main(["measure", *sys.argv[2:]])
