"""The base of the operators that work on the scene's design: one ``poll`` that says why it refuses.

Blender's own operators grey their button out and say why in its tooltip (``poll_message_set``).
An operator here names its reasons in ``refusal`` (None: it can run); ``poll`` adds the reason
every such operator shares (the scene has no design) and passes the message on. ``cancelled``
reports an error the user must act on, in one line, and cancels (no traceback for a user's mistake).
"""

from __future__ import annotations

from ...core_tracer.scene.reading import SceneError
from .. import reports
from . import properties, validity


class DesignOperator:
    """Mix in before ``bpy.types.Operator``; override ``refusal``."""

    @classmethod
    def refusal(cls, context) -> str | None:
        """Why the operator cannot run in ``context`` (the scene's design exists), or None."""
        return None

    @classmethod
    def poll(cls, context) -> bool:
        if not properties.poll_design(cls, context):
            return False
        reason = cls.refusal(context)
        if reason is not None:
            cls.poll_message_set(reason)
            return False
        return True

    def cancelled(self, error: Exception | str) -> set[str]:
        """Report ``error`` and cancel; an error of the design in the panel's words (``validity.message``)."""
        if isinstance(error, SceneError):
            import bpy

            return reports.cancelled(self, validity.message(bpy.context.scene, error))
        return reports.cancelled(self, str(error))
