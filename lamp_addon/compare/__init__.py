"""Compare with Cycles: the same design, camera and resolution rendered by the tracer and by Cycles,
side by side, from the Lamp tab (``ops``) or headless from the command line (``headless``).
"""

from ..registration import modules_factory


def modules() -> tuple:
    """The modules that register, in order."""
    from . import ops

    return (ops,)


register, unregister = modules_factory(modules)
