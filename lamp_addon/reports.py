"""How an operator ends: one line in Blender's report (the status bar and the Info editor) and the
result Blender expects from ``execute``, ``invoke`` or ``modal``.

A report is at most one line (``LINE`` characters), so Blender's status bar shows it whole. What
does not fit goes to the Info editor first, as lines of its own (``details``); the status bar then
shows the short line, reported last.
"""

from __future__ import annotations

import os
import re
import textwrap

LINE = 120  # characters: what the status bar of a 1920-pixel-wide window shows whole


def one_line(text: str) -> str:
    """``text`` on one line (runs of white space, line breaks included, become one space)."""
    return " ".join(str(text).split())


def details(operator, lines) -> None:
    """Report ``lines`` to the Info editor, each wrapped to ``LINE`` characters (for what a short
    report leaves out)."""
    for text in lines:
        # Whole words only, so the lines joined by spaces give the text back (a word longer than a
        # line, a hostile file's 10,000-letter key, stays one line of its own).
        for line in textwrap.wrap(one_line(text), LINE, break_long_words=False, break_on_hyphens=False):
            operator.report({"INFO"}, line)


# A file path in a message: a run of characters without white space, quotes or ";" that starts at a
# separator of this system's paths (or a drive letter) and holds another one.
_SEP = re.escape(os.sep) if os.sep == "/" else "[/\\\\]"
_PATH = re.compile(rf"(?<![\w.])(?:[A-Za-z]:)?{_SEP}[^\s\"';]*{_SEP}[^\s\"';]*?(?=:?(?:\s|$)|[\"';])")


def short_paths(text: str) -> str:
    """``text`` with each file path shortened to its file name."""
    return _PATH.sub(lambda m: os.path.basename(m.group(0).rstrip(os.sep)) or m.group(0), text)


def say(operator, level: str, message: str) -> None:
    """Report ``message`` at ``level`` in one line; a longer message goes whole to the Info editor
    first (``details``), and the status bar gets it with file paths shortened to file names, or its
    start."""
    text = one_line(message)
    if len(text) > LINE:
        details(operator, [text])
        text = short_paths(text)
        if len(text) > LINE:
            text = textwrap.shorten(text, LINE, placeholder=" ... (Info editor)")
    operator.report({level}, text)


def finished(operator, message: str, more=()) -> set[str]:
    """Report what ``operator`` did (details in ``more`` to the Info editor first) and finish it."""
    details(operator, more)
    say(operator, "INFO", message)
    return {"FINISHED"}


def cancelled(operator, message: str) -> set[str]:
    """Report why ``operator`` did nothing and cancel it."""
    say(operator, "ERROR", message)
    return {"CANCELLED"}
