"""The Study settings of the add-on's study tests: one axis of listed values."""

from __future__ import annotations


def one_axis(settings, parameter: str = "lens.ior", values: str = "1.45, 1.6", **more) -> None:
    """``Scene.lamp_study`` as a study of ``parameter`` over the listed ``values`` (no second axis),
    with the other settings given (``width=32, fit_lamp=False``...)."""
    settings.axis_1.parameter = parameter
    settings.axis_1.mode = "LIST"
    settings.axis_1.values = values
    settings.use_axis_2 = False
    for name, value in more.items():
        setattr(settings, name, value)
