"""``python -m core_tracer``: the standalone command line (see ``cli.py``)."""

from .cli.main import main

raise SystemExit(main())
