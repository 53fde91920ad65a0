"""Reading ``lamp-scene/1`` JSON with limits, and writing it back canonically.

A file is read only if it is a regular file of at most ``MAX_FILE_BYTES``, UTF-8, valid JSON,
with no key repeated in one object. Numbers beyond the float range are kept as ``HugeNumber`` so
that validation (``validate``) can name the field that holds them. Every failure is a
``SceneError`` whose text is the one-line message to show.
"""

from __future__ import annotations

import json
import math
import os
import re
import stat
from typing import Any

from .safe_text import show_key

MAX_FILE_BYTES = 1_000_000  # a lamp design is a few kB; refuse anything absurd before parsing


class SceneError(ValueError):
    """A user's mistake in a scene document; ``str()`` is the one-line message to show."""

    def __init__(self, path: str, message: str):
        self.path = path
        self.message = message
        super().__init__(f"{path}: {message}" if path else message)


# ---------------------------------------------------------------------------------------------
# Loading


def read_bounded(path: str | os.PathLike, max_bytes: int, *, shown: str | None = None,
                 not_regular: str = "not a regular file",
                 too_large: str = "file is {size} bytes; allowed at most {max_bytes} bytes",
                 unreadable: str = "cannot read the file ({reason})") -> bytes:
    """The bytes of a regular file of at most ``max_bytes`` (its size checked before reading, at
    most ``max_bytes + 1`` read), every failure a ``SceneError`` naming the file (``shown``) with the
    caller's words. Only regular files are opened: a pipe or a device could block or never end."""
    name = os.fspath(path)
    shown = name if shown is None else shown
    try:
        st = os.stat(name)
        if not stat.S_ISREG(st.st_mode):
            raise SceneError(shown, not_regular)
        if st.st_size > max_bytes:
            raise SceneError(shown, too_large.format(size=st.st_size, max_bytes=max_bytes))
        with open(name, "rb") as f:
            return f.read(max_bytes + 1)
    except OSError as e:
        raise SceneError(shown, unreadable.format(reason=e.strerror or e)) from None


def read_json(path: str | os.PathLike, max_bytes: int = MAX_FILE_BYTES) -> Any:
    """Read a JSON file with a size limit, turning every failure into a ``SceneError``.

    Only regular files are opened: a pipe or a device could block or never end."""
    name = os.fspath(path)
    raw = read_bounded(name, max_bytes)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise SceneError(name, "not UTF-8 text") from None
    return parse_json_text(text, name)


def parse_json_text(text: str, name: str = "") -> Any:
    """Decode JSON text. NaN and Infinity (which Python's json accepts) decode to floats, and a
    number too large for a float (``1e400``, or an integer of more than 4300 digits, which
    Python's int() refuses) to a ``HugeNumber``, so that validation can name the field that holds
    them. A key given twice in one object is refused (json would keep the last silently, so a
    file could say two things and mean one)."""
    duplicates: list[bool] = []

    def pairs_hook(pairs: list[tuple[str, Any]]) -> dict:
        obj = dict(pairs)
        if len(obj) == len(pairs):
            return obj
        duplicates.append(True)
        seen: set[str] = set()
        repeated = next(k for k, _ in pairs if k in seen or seen.add(k))
        return _Repeated(obj, repeated)

    try:
        doc = json.loads(text, parse_constant=float, parse_int=_parse_int, parse_float=_parse_float,
                         object_pairs_hook=pairs_hook)
    except RecursionError:
        raise SceneError(name, "not valid JSON: nested too deeply") from None
    except json.JSONDecodeError as e:
        raise SceneError(name, f"not valid JSON: {e.msg} at line {e.lineno} column {e.colno}") from None
    except ValueError as e:  # json's own limits, e.g. an integer of more than 4300 digits
        raise SceneError(name, f"not valid JSON: {str(e)[:120]}") from None
    if duplicates:
        where = _first_repeated(doc)
        prefix = f"{name}: " if name else ""
        raise SceneError(f"{prefix}{where}", "is given twice in one object; allowed once (which one is meant?)")
    return doc


class HugeNumber(float):
    """A JSON number beyond the float range, as written: infinite in value, shown by its digits."""

    text: str

    def __new__(cls, text: str) -> HugeNumber:
        number = super().__new__(cls, "-inf" if text.startswith("-") else "inf")
        number.text = text
        return number

    def shown(self) -> str:
        if len(self.text) <= 40:
            return self.text
        return f"a number of {sum(ch.isdigit() for ch in self.text)} digits"


_MAX_INT_DIGITS = 4300  # Python's default limit for int() of a decimal string


def _parse_int(text: str) -> int | float:
    return int(text) if len(text) <= _MAX_INT_DIGITS else HugeNumber(text)


def _parse_float(text: str) -> float:
    value = float(text)
    return HugeNumber(text) if math.isinf(value) else value


class _Repeated(dict):
    """A JSON object in which a key appeared more than once (the first such key is kept)."""

    def __init__(self, items: dict, repeated: str):
        super().__init__(items)
        self.repeated = repeated


def _first_repeated(doc: Any) -> str:
    """The field path of the first repeated key, in document order (iterative: depth is unbounded)."""
    stack: list[tuple[Any, str]] = [(doc, "")]
    while stack:
        node, path = stack.pop()
        if isinstance(node, _Repeated):
            return _join(path, node.repeated)
        if isinstance(node, dict):
            stack.extend((v, _join(path, k)) for k, v in reversed(list(node.items())))
        elif isinstance(node, list):
            stack.extend((v, f"{path}[{i}]") for i, v in reversed(list(enumerate(node))))
    return ""  # pragma: no cover - only called when the hook saw a repeated key


def _join(path: str, key: str) -> str:
    return f"{path}.{show_key(key)}" if path else show_key(key)


def scene_to_json(scene: dict) -> str:
    """The canonical JSON text of a scene: stable key order, 2-space indent, number lists on one line."""
    text = json.dumps(scene, indent=2, ensure_ascii=False)
    return _NUMBER_LIST.sub(lambda m: "[" + ", ".join(x.strip() for x in m.group(1).split(",")) + "]", text) + "\n"


_NUMBER_LIST = re.compile(r"\[\s*(-?[0-9][-+0-9.eE]*(?:,\s*-?[0-9][-+0-9.eE]*)*)\s*\]")
