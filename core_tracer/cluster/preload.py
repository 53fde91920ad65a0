"""A Dask worker preload: puts the folder that holds ``core_tracer`` first on the worker's path.

Dask imports this file by its path when a worker starts (``dask worker --preload
<checkout>/core_tracer/cluster/preload.py``; the local cluster passes it itself), so a worker can
unpickle the render tasks of a checkout that is not installed as a package. A worker that was
restarted after a fault runs it again. Standalone on purpose: it is imported before ``core_tracer``
can be.

glibc's allocator is told to keep freed memory mapped, as the project's own worker processes do
(``processes._KEEP_FREED_MEMORY``): Dask's default (``MALLOC_TRIM_THRESHOLD_`` 65536) hands every
large array back to the system, and a render then spends most of its time faulting pages in again
(a 6-variant 256 px study took 20 s instead of 4 s on two workers). ``mallopt`` sets it in the
running worker, so a studio's ``dask worker --preload`` gets it too.

A local cluster's workers (``LAMP_LOCAL_WORKER`` set) start a session of their own and ignore
Ctrl-C, as the project's own worker processes do (``start_new_session``): a terminal's Ctrl-C is
for the study, which stops them itself; and where the kernel shares the processors between
sessions (Linux's autogroup), each worker gets a session's share, as a pool worker does, not a
part of its parent's (on this shared 2-core machine that halved a Dask study's speed). A studio's
``dask worker`` is left as it is.
"""

import ctypes
import ctypes.util
import os
import signal
import sys

# mallopt parameters (glibc malloc.h): M_TRIM_THRESHOLD -1, M_MMAP_THRESHOLD -3; the values are
# processes._KEEP_FREED_MEMORY's.
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
TRIM_THRESHOLD, MMAP_THRESHOLD = 536870912, 268435456

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

if os.environ.get("LAMP_LOCAL_WORKER") == "1":
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(os, "setsid"):
        try:
            os.setsid()
        except OSError:  # a session leader already
            pass

if sys.platform.startswith("linux"):
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        libc.mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD)
        libc.mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD)
    except (OSError, AttributeError):  # another C library: it has its own policy
        pass
