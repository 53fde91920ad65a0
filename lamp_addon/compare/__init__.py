"""Compare with Cycles: the same design, camera and resolution rendered by the tracer and by Cycles,
side by side, from the Lamp tab (``ops``) or headless from the command line (``headless``).

- ``comparison``: one comparison step by step (``CompareRun``) and its image.
- ``settings``: the Cycles and scene settings a comparison sets, and putting them back.
- ``scope``: what is compared: the design, whatever else is in the file.
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order."""
    from . import ops

    return (ops,)


register, unregister = modules_factory(modules)
