"""Writes that never leave a half-written file: write a temporary file beside, then rename.

A folder of outputs (a render's passes, a study's variants) is written the same way, whole: into a
temporary folder beside, which then replaces the folder (``atomic_folder``).

The temporary file is created with mode 0666 less the umask, as any program's file (a teammate
can read what was written to a shared folder), and its name is chosen before it is created, so
a Ctrl-C or SIGTERM that lands at any instant still finds and removes it.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import shutil
import signal
import threading
from collections.abc import Callable, Iterator

from .checkpoints import checkpoint

# The folder that holds ``core_tracer`` (the repository, or the installed extension's folder).
EXTENSION_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


_NO_HARD_LINKS = {errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EXDEV, errno.EMLINK, errno.ENOSYS}


class TargetExistsError(FileExistsError):
    """``atomic_path(..., overwrite=False)`` found the file there already; nothing was changed."""


def temporary_name(path: str | os.PathLike) -> str:
    """A fresh, unguessable name beside ``path`` with the same suffix (writers that choose the
    format by the extension still work): ``.<stem>.<random>.tmp<suffix>``."""
    final = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(final))
    base, suffix = os.path.splitext(os.path.basename(final))
    return os.path.join(folder, f".{base}.{secrets.token_hex(8)}.tmp{suffix}")


def _create(tmp: str) -> None:
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
    os.close(fd)


def _as_final(e: OSError, final: str) -> OSError:
    """The same error naming the user's file, not the temporary one."""
    return type(e)(e.errno, e.strerror, final) if e.errno is not None else e


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, *, overwrite: bool = True) -> Iterator[str]:
    """Yield a temporary path beside ``path``; on success it becomes ``path``, on failure (or an
    interrupt at any moment) it is removed.

    ``overwrite=False`` never replaces a file that is there (even one another process creates
    meanwhile): ``TargetExistsError`` then, and exactly one of several concurrent writers wins."""
    final = os.fspath(path)
    tmp = temporary_name(final)  # named first: the cleanup below knows it whenever an interrupt lands
    try:
        try:
            _create(tmp)
        except FileExistsError:  # 64 random bits met an existing name: not ours, never remove it
            tmp = ""
            raise
        except OSError as e:
            raise _as_final(e, final) from None
        checkpoint("write:created")
        yield tmp
        checkpoint("write:written")
        try:
            if overwrite:
                os.replace(tmp, final)
            else:
                _link_no_clobber(tmp, final)
        except TargetExistsError:
            raise
        except OSError as e:
            raise _as_final(e, final) from None
    except BaseException:
        if tmp:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        raise
    if not overwrite:
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def _link_no_clobber(tmp: str, final: str) -> None:
    """Give the complete file ``tmp`` the name ``final`` unless that name exists: link(2) fails
    atomically when it does. Where a file system has no hard links, an exclusive create reserves
    the name first (its empty file is visible for a moment, never a half-written one)."""
    try:
        os.link(tmp, final)
        return
    except FileExistsError:
        raise TargetExistsError(errno.EEXIST, "exists already", final) from None
    except OSError as e:
        if e.errno not in _NO_HARD_LINKS:
            raise
    try:
        fd = os.open(final, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    except FileExistsError:
        raise TargetExistsError(errno.EEXIST, "exists already", final) from None
    os.close(fd)
    os.replace(tmp, final)


def atomic_write_bytes(path: str | os.PathLike, data: bytes, *, overwrite: bool = True) -> None:
    with atomic_path(path, overwrite=overwrite) as tmp:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())


def atomic_write_text(path: str | os.PathLike, text: str, *, overwrite: bool = True) -> None:
    atomic_write_bytes(path, text.encode("utf-8"), overwrite=overwrite)


def check_writable(path: str | os.PathLike) -> None:
    """Raise ``OSError`` naming ``path`` if a file cannot be written there: its folder is missing
    or read-only, or ``path`` is a folder. Done before long work, so it is not lost at the end."""
    final = os.fspath(path)
    if os.path.isdir(final):
        raise IsADirectoryError(errno.EISDIR, "is a folder; allowed a file name", final)
    tmp = temporary_name(final)
    try:
        _create(tmp)
    except FileExistsError:  # 64 random bits met an existing name: not ours; the folder is writable
        return
    except BaseException as e:
        with contextlib.suppress(OSError):
            os.unlink(tmp)  # an interrupt may land after the file was made
        if isinstance(e, OSError):
            raise _as_final(e, final) from None
        raise
    os.unlink(tmp)


@contextlib.contextmanager
def signals_deferred() -> Iterator[None]:
    """SIGINT and SIGTERM wait until the block is done (a few renames), then take effect: the
    block is never left half-done by them."""
    if not hasattr(signal, "pthread_sigmask") or threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


class FolderInUseError(OSError):
    """The folder holds files that are not of the kind written there: it is never replaced."""


def check_replaceable_folder(path: str | os.PathLike, replaceable: Callable[[str], bool], what: str) -> None:
    """Raise ``FolderInUseError`` naming ``path`` unless it is missing, or a folder (not a link)
    holding only regular files whose names ``replaceable`` accepts: the outputs of an earlier run,
    which ``atomic_folder`` replaces whole. A folder holding anything else is the user's."""
    final = os.fspath(path)
    if not os.path.lexists(final):
        return
    if os.path.islink(final) or not os.path.isdir(final):
        raise FolderInUseError(errno.EEXIST, f"is not a folder of {what}; allowed a new folder or one of an "
                                             "earlier run", final)
    for entry in os.scandir(final):
        if not (replaceable(entry.name) and entry.is_file(follow_symlinks=False)):
            raise FolderInUseError(errno.ENOTEMPTY, f"holds other files than {what} ({entry.name[:60]!r}); "
                                                    "allowed a new folder or one of an earlier run, which is "
                                                    "replaced whole", final)


@contextlib.contextmanager
def atomic_folder(path: str | os.PathLike, replaceable: Callable[[str], bool], what: str) -> Iterator[str]:
    """Yield a new temporary folder beside ``path``; on success it becomes ``path`` whole: a folder
    there (only of files ``replaceable`` accepts, see ``check_replaceable_folder``) is replaced, never
    mixed with. On failure or an interrupt at any moment the temporary folder is removed and
    ``path`` is as it was."""
    final = os.path.normpath(os.path.abspath(os.fspath(path)))
    tmp = temporary_name(final)  # named first: the cleanup below knows it whenever an interrupt lands
    try:
        try:
            os.mkdir(tmp, 0o777)  # the umask applies, as to any program's folder
        except FileExistsError:  # 64 random bits met an existing name: not ours, never remove it
            tmp = ""
            raise
        except OSError as e:
            raise _as_final(e, final) from None
        yield tmp
        checkpoint("folder:written")
        with signals_deferred():
            check_replaceable_folder(final, replaceable, what)  # again: the render took a while
            old = temporary_name(final) if os.path.lexists(final) else ""
            if old:
                os.rename(final, old)
            try:
                os.rename(tmp, final)
            except OSError as e:
                if old:
                    os.rename(old, final)
                raise _as_final(e, final) from None
            tmp = ""
            if old:
                shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
        raise


def is_pass_file(name: str) -> bool:
    """A render's pass image (``--passes``): ``<pass>.exr``."""
    return name.endswith(".exr") and not name.startswith(".")
