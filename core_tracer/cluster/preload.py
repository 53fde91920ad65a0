"""A Dask worker preload: puts the folder that holds ``core_tracer`` first on the worker's path.

Dask imports this file by its path when a worker starts (``dask worker --preload
<checkout>/core_tracer/cluster/preload.py``; the local cluster passes it itself), so a worker can
unpickle the render tasks of a checkout that is not installed as a package. A worker that was
restarted after a fault runs it again. Standalone on purpose: it is imported before ``core_tracer``
can be.

A local cluster's workers (``LAMP_LOCAL_WORKER`` set) also ignore Ctrl-C: a terminal sends it to
the whole process group, and the study that started them stops them itself, as the project's own
worker processes do; a studio's ``dask worker`` keeps stopping on Ctrl-C.
"""

import os
import signal
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

if os.environ.get("LAMP_LOCAL_WORKER") == "1":
    signal.signal(signal.SIGINT, signal.SIG_IGN)
