"""The paper's renderer: camera, per-lamp tables (``lamp_table``), one module per part type with
its ray-surface intersection (``parts``), surface optics of equations (1)-(3) and Fresnel
(``optics``), Table 1's path classes (``paths``) and the wavefront tracer that walks the
ray-tracing tree (``engine``)."""
