"""The wavefront tracer of the paper's improved ray tracing, along the ray's path:

- ``render``: the render entry (``render``, ``render_passes``, ``make_context``, ``RenderResult``).
- ``schedule``: bands of rows and who traces them (threads, a ``band_pool``), in the image's order.
- ``carried``: a band's deep branches traced along with the next band's rays.
- ``adaptive``: which samples a band traces (adaptive sampling: pilot samples, neighbourhoods).
- ``sampling``: samples of pixels as eye rays in groups, traced and summed per pixel.
- ``walk``: one generation of the ray-tracing tree: nearest surfaces, absorption, the step; a
  context's ``walker`` replaces how rays find surfaces (the free-form tracer's meshes, ``freeform.render``).
- ``eyes``: eye rays and what they meet first (background, body, a lens's outer face).
- ``surfaces``: what happens at a surface: the reflector, and the one Fresnel split of lens and plate faces.
- ``context``: everything constant during one render; ``rays``: the rays and the passes they add to.
"""

from .rays import PASS_NAMES
from .render import RenderResult, lens_pixels, make_context, render, render_passes
from .schedule import RenderCancelled

__all__ = ["PASS_NAMES", "RenderCancelled", "RenderResult", "lens_pixels", "make_context", "render", "render_passes"]
