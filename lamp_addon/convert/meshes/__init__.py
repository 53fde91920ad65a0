"""Tessellated lamp parts: vertices in mm, faces, smoothing groups (numpy; no Blender data).

Every part is built to a chord tolerance: no point of any triangle of the mesh lies further than
``builder.CHORD_TOLERANCE_MM`` (0.05 mm; Convert to Free-form's 0.0125 mm, ``builder.tolerances``) from
the analytic surface the tracer uses (docs/model.md §3).
The tessellation is chosen from that tolerance and then *measured* (``MeshData.max_deviation``: the
largest distance to the analytic surface over 28 sample points on every triangle of both diagonal
splits of every quad); curved surfaces are refined until the measurement is within ``SAMPLED_MARGIN``
times the tolerance (cylinders follow the exact sagitta r(1 - cos(pi/n))), up to a cap
(``MAX_CELL_SUBDIVISION``, ``MAX_SEGMENTS``) that only extreme designs reach (cut caps close to
hemispheres) — then ``max_deviation`` reports what was achieved and the build operator says so.

Coordinates are the model's (docs/model.md §2): x right, y into the lamp (the lens front face is y = 0),
z up, millimetres. Lamp parts are given relative to their lamp's axis (x = z = 0 on the axis); the
body in scene coordinates. Faces are wound so that normals point out of the solid: out of the lens
glass, out of the bulb, socket and body, and from the reflector toward the lamp interior.

- ``builder``: the mesh builder and what every part shares (the tolerance, measuring, rim polygons,
  the lens side wall).
- ``lens``: the lens solid of a lamp, by the kind of its cuts: ``fisheye`` (spherical lenslets),
  ``sawtooth``, ``flutes``; ``wrap`` (a cylindrical lens and the body that curves round it) and
  ``prism_plate`` (the prism plate and its housing) are lenses of their own collections.
- ``parts``: the reflector, bulb, socket and body.
"""
