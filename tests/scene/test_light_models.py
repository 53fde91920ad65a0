"""Which fields each light model uses (core_tracer.scene.light_models), against the engine's own lists."""

from __future__ import annotations

from core_tracer.photometry import sources
from core_tracer.scene import light_models, photometric_checks
from core_tracer.scene import spec as S


def test_the_named_bulbs_are_the_sources_bulbs():
    assert set(S.BULB_TYPES) == set(sources.BULB_TYPES)
    for name, kind in sources.BULB_TYPES.items():
        assert photometric_checks.BULB_STATES[name] == tuple(kind.states), name
        assert set(kind.states) <= set(S.BULB_STATES), name


def test_photometric_fields_are_not_the_paper_modes():
    photometric = {(path, key) for path, sec in S.iter_sections() for key in sec.fields
                   if not isinstance(sec.fields[key], (S.Section, S.ListOf))
                   and light_models.is_photometric_only(sec, key)}
    keys = {f"{path}.{key}".lstrip(".") for path, key in photometric}
    assert "lamps[].bulb.flux_lm" in keys and "light.illuminance_lux" in keys and "camera.ev100" in keys
    assert "lamps[].bulb.intensity" not in keys
    for _path, sec in S.iter_sections():
        for key in sec.fields:
            assert not (light_models.is_paper_only(sec, key) and light_models.is_photometric_only(sec, key)), key


def test_used_follows_the_light_model():
    def custom(_key):
        return "custom"

    def pmma(_key):
        return "pmma"

    assert light_models.used(S.BULB, "intensity", "paper", custom)
    assert not light_models.used(S.BULB, "intensity", "photometric", custom)
    assert light_models.used(S.BULB, "flux_lm", "photometric", custom)
    assert not light_models.used(S.BULB, "flux_lm", "paper", custom)
    assert light_models.used(S.LENS, "ior", "paper", pmma)  # the paper's index is always the lens's
    assert not light_models.used(S.LENS, "ior", "photometric", pmma)  # the material's
    assert light_models.used(S.LENS, "ior", "photometric", custom)
    assert light_models.used(S.PRISM_PLATE, "ior", "photometric", pmma)  # it shapes the rings in both modes
    assert not light_models.used(S.LENS, "transmitted_color", "photometric", custom)


def test_free_form_roles_show_the_fields_of_the_light_model_as_the_parts_they_stand_for():
    lens, bulb = S.FREEFORM_ROLE_SECTIONS["lens"], S.FREEFORM_ROLE_SECTIONS["bulb"]
    pmma = {"material": "pmma"}.get
    assert light_models.used(lens, "absorption", "paper", pmma)
    assert not light_models.used(lens, "absorption", "photometric", pmma)  # its filter stands for it
    assert not light_models.used(lens, "filter", "paper", pmma)
    assert light_models.used(lens, "filter", "photometric", pmma)
    assert not light_models.used(lens, "ior", "photometric", pmma)  # the material's
    assert light_models.used(lens, "ior", "photometric", {"material": "custom"}.get)
    assert not light_models.used(bulb, "intensity", "photometric", pmma)
    assert light_models.used(bulb, "radius", "photometric", pmma)
    assert not light_models.used(bulb, "radius", "paper", pmma)
    for role in ("socket", "side_wall"):  # unlit in the photometric mode
        assert not light_models.used(S.FREEFORM_ROLE_SECTIONS[role], "color", "photometric", pmma)
