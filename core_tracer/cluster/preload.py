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

Inside Blender the project's package is ``bl_ext.<repository>.lamp_styling.core_tracer``, and a task
sent from there names its functions so; a worker finds ``bl_ext...core_tracer.x`` as this checkout's
``core_tracer.x`` (``BlenderNames``), the packages above it as empty ones.

A local cluster's workers (``LAMP_LOCAL_WORKER`` set) start a session of their own and ignore
Ctrl-C, as the project's own worker processes do (``start_new_session``): a terminal's Ctrl-C is
for the study, which stops them itself; and where the kernel shares the processors between
sessions (Linux's autogroup), each worker gets a session's share, as a pool worker does, not a
part of its parent's (on this shared 2-core machine that halved a Dask study's speed). A studio's
``dask worker`` is left as it is.
"""

import ctypes
import ctypes.util
import importlib
import importlib.abc
import importlib.machinery
import os
import signal
import sys
import types

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


class _Alias(importlib.abc.Loader):
    def __init__(self, module):
        self.module = module

    def create_module(self, spec):
        return self.module

    def exec_module(self, module):
        pass


class BlenderNames(importlib.abc.MetaPathFinder):
    """``bl_ext.<repository>.<extension>`` as empty packages, and ``...core_tracer[.x]`` under them as
    ``core_tracer[.x]``."""

    PREFIX = "bl_ext"

    def find_spec(self, fullname, path=None, target=None):
        parts = fullname.split(".")
        if parts[0] != self.PREFIX:
            return None
        if "core_tracer" in parts:
            real = ".".join(parts[parts.index("core_tracer"):])
            module = importlib.import_module(real)
            return importlib.machinery.ModuleSpec(fullname, _Alias(module), is_package=hasattr(module, "__path__"))
        package = types.ModuleType(fullname)
        package.__path__ = []
        return importlib.machinery.ModuleSpec(fullname, _Alias(package), is_package=True)


if not any(isinstance(f, BlenderNames) for f in sys.meta_path):
    sys.meta_path.insert(0, BlenderNames())  # before the path finder, which would load a second copy
