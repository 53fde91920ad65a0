"""The paper's renderer: camera, per-lamp tables and ray-surface intersections (``geometry``), surface
optics of equations (1)-(3) and Fresnel (``optics``), Table 1's path classes (``paths``) and the
wavefront tracer that walks the ray-tracing tree (``tracer``)."""
