"""The standalone command line, ``python -m core_tracer``: ``main`` parses and dispatches, one module
per command (``render``, ``validate``, ``presets``, ``study``), ``common`` holds what they share."""
