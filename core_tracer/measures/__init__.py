"""Measures a lamp engineer signs, from a photometric design (numpy only, no bpy):

- ``directions``: the (H, V) angles of the regulations and the unit vectors of the light.
- ``intensity``: luminous intensity I(H, V) in cd from orthographic renders, with its standard
  error; goniometer sweeps.
- ``light_tracing``: the second, independent estimator of I: light traced forward from the bulbs
  through the same optics into cones of directions.
"""
