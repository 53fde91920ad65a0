# SPDX-License-Identifier: GPL-3.0-or-later
"""Blender needs ``__init__.py`` at the extension root; the add-on itself lives in ``lamp_addon``."""

from .lamp_addon import register, unregister

__all__ = ("register", "unregister")
