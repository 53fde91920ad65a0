"""Worker processes of core_tracer (a study's renders, a render's bands): how they are started.

A worker runs the interpreter that runs this code (``sys.executable``: the venv's python for the
CLI and the tests, Blender's own Python inside Blender) in isolated mode (``-I``: no user
site-packages, no PYTHON* variables), with the folder that holds ``core_tracer`` first on its path,
so that it imports ``core_tracer`` as a top-level package whatever name this process knows it by.
Its numpy runs single-threaded (OMP/BLAS threads = 1): the workers are the parallelism.

A run's temporary files and folders are named ``<prefix><its process id>-...``: a run killed with
SIGKILL cannot remove them, and the next run does (``remove_orphans``).
"""

from __future__ import annotations

import os
import shutil
import stat
import sys
import tempfile

from .fileio import EXTENSION_ROOT

# The folder that holds the core_tracer package: a worker's import root.
PACKAGE_ROOT = EXTENSION_ROOT
_SINGLE_THREAD = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                         "NUMEXPR_NUM_THREADS", "VECLIB_MAXIMUM_THREADS")}


def worker_command(module: str, *arguments: str, python: str | None = None) -> list[str]:
    """The command line of a worker running ``core_tracer.<module>``'s ``main()`` with
    ``arguments`` after the import root in its ``sys.argv``."""
    bootstrap = (f"import sys; sys.path.insert(0, sys.argv[1]); "
                 f"from core_tracer.{module} import main; raise SystemExit(main())")
    return [python or sys.executable, "-I", "-c", bootstrap, PACKAGE_ROOT, *arguments]


# glibc's allocator returns every large array to the system when it is freed, and the next band's
# fresh arrays then fault their pages in again: 15-60 thousand page faults a render, about 5 % of
# its CPU. A worker keeps them mapped instead (about 9 MB more at its peak). Other C libraries
# ignore these variables.
_KEEP_FREED_MEMORY = {"MALLOC_MMAP_THRESHOLD_": "268435456", "MALLOC_TRIM_THRESHOLD_": "536870912"}


def worker_environment() -> dict[str, str]:
    env = dict(os.environ)
    env.update(_SINGLE_THREAD)
    for name, value in _KEEP_FREED_MEMORY.items():
        env.setdefault(name, value)  # an administrator's own setting wins
    env["PYTHONNOUSERSITE"] = "1"
    return env


def python_runs_workers(python: str | None = None) -> bool:
    """Whether ``python`` (``sys.executable`` by default) is a Python interpreter: older Blender
    builds, and programs embedding Python, give their own executable there, which must never be
    started as a worker."""
    path = python or sys.executable
    return bool(path) and os.path.basename(path).lower().startswith("python") and os.path.isfile(path)


def remove_orphans(prefix: str, temp: str | None = None) -> list[str]:
    """Remove the temporary files and folders ``<temp>/<prefix><pid>-...`` whose process is gone
    (killed with SIGKILL, or by a power cut: no cleanup could run); returns them. Only this user's
    entries whose process id no longer exists are touched, never through a link. POSIX only
    (elsewhere ``os.kill`` cannot ask whether a process exists without ending it)."""
    if os.name != "posix":
        return []
    temp = temp or tempfile.gettempdir()
    removed = []
    try:
        names = os.listdir(temp)
    except OSError:
        return removed
    for name in names:
        pid_text = name[len(prefix):].split("-", 1)[0]
        if not name.startswith(prefix) or not pid_text.isdigit() or len(pid_text) > 10:
            continue
        path = os.path.join(temp, name)
        try:
            st = os.lstat(path)
        except OSError:
            continue
        if stat.S_ISLNK(st.st_mode) or st.st_uid != os.getuid() or _alive(int(pid_text)):
            continue
        if stat.S_ISDIR(st.st_mode):
            shutil.rmtree(path, ignore_errors=True)
        elif stat.S_ISREG(st.st_mode):
            try:
                os.unlink(path)
            except OSError:
                continue
        else:
            continue
        removed.append(path)
    return removed


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True  # someone else's process, or a number no process has: leave it
    return True


class ImagesInOrder:
    """The progress of a run that fills ``images``, one slot per variant or cell (None until its
    image is back): a study's processes (``study.run``) and a cluster's cells (``cluster.engine``)."""

    images: list

    @property
    def total(self) -> int:
        return len(self.images)

    @property
    def done(self) -> int:
        return sum(image is not None for image in self.images)
