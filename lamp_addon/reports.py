"""How an operator ends: one line in Blender's report (the status bar and the Info editor) and the
result Blender expects from ``execute``, ``invoke`` or ``modal``."""

from __future__ import annotations


def finished(operator, message: str) -> set[str]:
    """Report what ``operator`` did and finish it."""
    operator.report({"INFO"}, message)
    return {"FINISHED"}


def cancelled(operator, message: str) -> set[str]:
    """Report why ``operator`` did nothing and cancel it."""
    operator.report({"ERROR"}, message)
    return {"CANCELLED"}
