"""Text from a user's file made safe to print: one line, escaped, bounded.

A hostile file can hold keys or strings with carriage returns, terminal escape sequences, lone
surrogates (which no UTF-8 terminal can encode) or hundreds of kilobytes; a message that quotes
them must still be one readable line.
"""

from __future__ import annotations

MAX_MESSAGE = 400
MAX_KEY = 60  # a key quoted in a field path


def printable(text: str, limit: int = MAX_MESSAGE) -> str:
    """One line of plain text: control characters, lone surrogates and undecodable bytes escaped,
    length bounded (``...`` marks a cut)."""
    out = []
    for ch in text[: limit + 1]:
        code = ord(ch)
        if 0xDC80 <= code <= 0xDCFF:  # an undecodable byte of a file name (surrogateescape)
            out.append(f"\\x{code - 0xDC00:02x}")
        elif ch.isprintable():
            out.append(ch)
        else:
            out.append(ch.encode("unicode_escape").decode("ascii"))
    line = "".join(out)
    return line if len(line) <= limit else line[: limit - 3] + "..."


def show_key(key: str) -> str:
    """A key of a JSON object as a field path quotes it."""
    return printable(key, MAX_KEY)


def has_surrogate(text: str) -> bool:
    """Whether ``text`` holds a lone surrogate (``"\\ud800"`` in JSON): not a character, and no
    UTF-8 file, terminal or Blender property can store it."""
    return any(0xD800 <= ord(ch) <= 0xDFFF for ch in text)
