# SPDX-License-Identifier: GPL-3.0-or-later
"""The settings of an optimisation (``Scene.lamp_optimise``) and the last one's outcome.

An optimisation is a ``lamp-optimise/1`` file (docs/cluster.md); one without ``base`` starts from
the design in this scene. ``last`` keeps what the last search found, for the panel and for applying
a trial to the design.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import bpy
from bpy.props import IntProperty, StringProperty

from ..scene_settings import SceneSettings


@dataclass
class Outcome:
    name: str
    objectives: list[str]
    best: list[tuple[int, dict, list[float]]] = field(default_factory=list)  # (trial, design values, values)
    folder: str = ""
    summary: str = ""


_last: list[Outcome] = []


def last() -> Outcome | None:
    return _last[0] if _last else None


def remember(outcome: Outcome) -> None:
    _last[:] = [outcome]


@bpy.app.handlers.persistent
def _forget(*_args) -> None:
    """A file opened (or a new one): the last optimisation was another file's, not shown here."""
    _last.clear()


class LAMP_PG_optimise(SceneSettings, bpy.types.PropertyGroup):
    scene_attribute = "lamp_optimise"
    scene_name = "Lamp Optimisation"
    scene_description = "Settings of the design optimisation"

    file: StringProperty(name="File", subtype="FILE_PATH", default="",
                         description="The optimisation, a lamp-optimise/1 JSON file (docs/cluster.md); without a "
                                     "base it starts from this design")
    scheduler: StringProperty(name="Scheduler", default="local", maxlen=300,
                              description="Where trials render: \"local\" (in Blender, one after the other) or a "
                                          "Dask scheduler's address, tcp://HOST:8786")
    trials: IntProperty(name="Trials", default=0, min=0, max=10000,
                        description="Finish this many trials in all (0: as many as the file says)")
    choice: IntProperty(name="Design", default=1, min=1, max=64,
                        description="Which of the best designs to apply (several for a Pareto front)")

    @classmethod
    def register(cls):
        super().register()
        if _forget not in bpy.app.handlers.load_post:
            bpy.app.handlers.load_post.append(_forget)

    @classmethod
    def unregister(cls):
        super().unregister()
        if _forget in bpy.app.handlers.load_post:
            bpy.app.handlers.load_post.remove(_forget)


classes = (LAMP_PG_optimise,)


register, unregister = bpy.utils.register_classes_factory(classes)
