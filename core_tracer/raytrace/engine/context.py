"""Everything constant during one render of a parametric design: the lamps' table, the parts a
ray can meet, the body's box and its picture on the screen, the lighting (``Lighting``)."""

from __future__ import annotations

import numpy as np

from ...scene.derived import body_wraps
from .. import spectral, sunlight
from ..camera import Camera
from ..lamp_table import LampTable
from ..lighting import Lighting
from ..parts import body_box, parts_for
from .rays import BY_PASS

# The depth limit (docs/photometric.md, light guides): at most this many segments along one branch;
# the branches still alive there end, counted in ``Band.cut_at_depth`` and the render's statistics.
MAX_DEPTH = 64
# A light guide's paths are long: light runs along the rod by total internal reflection, one segment
# a reflection, some 30 to 100 of them from a prism to the LED along a guide 50 to 150 mm long and 4 to
# 6 mm thick (a ray at the critical angle meets a wall every thickness / tan 42° of its length). A
# lamp with a guide is walked to this depth instead.
GUIDE_MAX_DEPTH = 256


class Context(Lighting):
    """Everything constant during one render."""

    walker = None  # how rays find surfaces: the parametric lamps' own walk (``walk.Walker``)
    planes = BY_PASS  # what a band accumulates: the passes, or each source's light (``rays.BySource``)

    def __init__(self, scene: dict, camera: Camera, record_transitions: bool, samples: int, filter_name: str,
                 adaptive_threshold: float = 0.0, bands: int | None = None):
        super().__init__(scene, bands)
        self.camera = camera
        self.samples = samples
        # the emitter edges' extra samples per sample (``edges``; 0: none)
        self.edge_samples = int(scene["image"].get("edge_samples", 0))
        self.filter_name = filter_name
        self.adaptive_threshold = adaptive_threshold
        self.lamps = LampTable.from_scene(scene)
        self.throughput = None  # the photometric mode's deferred bands (``spectral.Throughput``)
        if self.photometric is not None:
            self.lamps = spectral.photometric_lamps(self.lamps, scene, self.photometric.bands)
            self.throughput = spectral.Throughput.of(self.lamps, self.photometric.bands)
        self.parts = parts_for(self.lamps)  # the parts a ray can meet, in PARTS's order
        # else no ray meets a prism plate, its housing or a light guide (whose rod is the plate's medium)
        self.plates = bool(self.lamps.ring_count.any()) or self.lamps.guide is not None
        self.leds = self.lamps.any_leds  # else no ray meets an LED die
        self.max_depth = GUIDE_MAX_DEPTH if self.lamps.guide is not None else MAX_DEPTH  # ``walk.depth_limit``
        body = scene["body"]
        self.box_lo, self.box_hi = body_box.body_box(body)
        self.window = body_box.screen_window(camera, self.box_lo, self.box_hi)  # the pixels that can see the body
        self.wraps = body_wraps(scene)  # the curved ends of the front, none for flat lenses
        self.body = body
        self.body_color = (np.asarray(body["color"]) if self.photometric is None
                           else self.photometric.reflectance(body["color"]))  # photometric: Smits's reflectance
        self.phantom_lamps = sunlight.PhantomLamps.of(self.sun, self.lamps)  # T_sun and the outline per lamp
        self.phantom = scene["light"].get("phantom", False) and bool(self.phantom_lamps.lets_in.any())
        self.record = record_transitions
