"""The scene settings a comparison changes, and the values it sets.

Cycles settings. The tracer follows every specular branch to the end (cut-off 0.1 %); Cycles
follows one sampled path per sample, so the bounce limits must cover the longest specular chain
camera -> lens -> cuts -> reflector -> ... -> bulb: ``transmission_bounces`` >= 8,
``glossy_bounces`` >= 6, ``max_bounces`` >= 12; caustics stay on and glossy filtering and
clamping off, since the bulb is seen through the lens and in the mirror. Denoising and
adaptive sampling are off so that the result is the plain Monte Carlo estimate. The tracer
takes one ray through each pixel centre; Cycles integrates over its pixel filter. A box filter
of the smallest width (0.01 px) makes Cycles sample the same pixel centres, so edges alias the
same way in both halves and the per-pixel difference measures the models, not the filters.

During the comparison the scene shows renders on the Standard view transform (``STANDARD_VIEW``),
under which the tracer's linear RGB (the paper's stimulus values) and Cycles' radiance are shown the
same way; like every setting the comparison changes, it is put back afterwards (``SceneSettings``).
"""

from __future__ import annotations

MIN_BOUNCES = {"max_bounces": 12, "transmission_bounces": 8, "glossy_bounces": 6}
CYCLES_SETTINGS = {
    "device": "CPU",
    "use_denoising": False,
    "use_adaptive_sampling": False,
    "caustics_reflective": True,
    "caustics_refractive": True,
    "blur_glossy": 0.0,
    "sample_clamp_direct": 0.0,
    "sample_clamp_indirect": 0.0,
    "pixel_filter_type": "BOX",
    "filter_width": 0.01,
    "seed": 0,
    "use_animated_seed": False,
}
# With more than one sample per pixel the tracer spreads them by Cycles' own default pixel filter
# (core_tracer.raytrace.pixel_filter), so Cycles keeps that filter instead of sampling the centre.
ANTIALIASED_FILTER = {"pixel_filter_type": "BLACKMAN_HARRIS", "filter_width": 1.5}


def cycles_settings(tracer_samples: int) -> dict:
    """Cycles' settings for a comparison with the tracer at ``tracer_samples`` per pixel: one
    sample is the pixel centre (a box 0.01 px wide), more are Blackman-Harris 1.5 px as the tracer's."""
    return {**CYCLES_SETTINGS, **(ANTIALIASED_FILTER if tracer_samples > 1 else {})}


# Renders shown as their linear values map to the display: Standard, no look, no exposure.
STANDARD_VIEW = {"view_transform": "Standard", "look": "None", "exposure": 0.0, "gamma": 1.0,
                 "use_curve_mapping": False}

class SceneSettings:
    """Settings changed for the comparison with their old values, put back by ``restore``.

    Old values are recorded the first time a setting is changed, before any of the values given
    with it are set (setting the file format can change the colour depth). ``restore`` puts them
    back in the order they were first set, so dependent settings stay valid (format before depth).
    A setting that no longer holds the comparison's value was changed by the user meanwhile (the
    interface is live during the modal comparison) and is left as the user set it."""

    def __init__(self) -> None:
        self._old: dict[tuple[int, str], tuple[object, str, object]] = {}  # (owner, key) -> (owner, key, old)
        self._ours: dict[tuple[int, str], object] = {}

    def set(self, owner, **values) -> None:
        for key in values:
            self._old.setdefault((owner.as_pointer(), key), (owner, key, getattr(owner, key)))
        for key, value in values.items():
            setattr(owner, key, value)
            self._ours[(owner.as_pointer(), key)] = getattr(owner, key)  # as Blender stores it

    def restore(self) -> list[str]:
        """Put the old values back; returns what could not be put back (normally nothing)."""
        problems = []
        unchanged = [(owner, key, old) for slot, (owner, key, old) in self._old.items()
                     if getattr(owner, key) == self._ours[slot]]  # all decided before any is put back
        for owner, key, old in unchanged:
            try:
                setattr(owner, key, old)
            except (AttributeError, TypeError, ValueError) as e:
                problems.append(f"{key}: {e}")
        self._old.clear()
        self._ours.clear()
        return problems


def exr_output_values(settings) -> dict:
    """Output settings under which ``save_render`` writes the exact linear values."""
    values = {"file_format": "OPEN_EXR", "color_depth": "32", "exr_codec": "ZIP"}
    if hasattr(settings, "media_type"):  # Blender 5.0: the format list depends on the media type
        values = {"media_type": "IMAGE", **values}
    if hasattr(settings, "color_management"):
        values["color_management"] = "FOLLOW_SCENE"
    return values
