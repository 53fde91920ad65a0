"""The modal jobs share one base and one registry; the operator modules import no circle."""

from __future__ import annotations

import re

import pytest
from helpers import ROOT, package_imports

from lamp_addon import jobs

ADDON = ROOT / "lamp_addon"


def test_one_run_at_a_time_per_kind():
    first, second = object(), object()
    jobs.claim("test.kind", first, "busy")
    try:
        jobs.claim("test.kind", first, "busy")  # claiming again is harmless
        with pytest.raises(jobs.JobBusy, match="busy"):
            jobs.claim("test.kind", second, "busy")
        jobs.claim("test.other", second, "busy")  # another kind may run meanwhile
        assert jobs.running("test.kind") is first and jobs.running("test.other") is second
        jobs.release("test.kind", second)  # not the run under way: kept
        assert jobs.running("test.kind") is first
    finally:
        jobs.release("test.kind")
        jobs.release("test.other")
    assert jobs.running("test.kind") is None and jobs.running("test.other") is None


def test_the_modal_operators_share_the_base(lamp_addon):
    for module, name in ((lamp_addon.render.ops, "LAMP_OT_render_tracer"),
                         (lamp_addon.compare.ops, "LAMP_OT_compare_cycles"),
                         (lamp_addon.study.ops, "LAMP_OT_study_run")):
        operator = getattr(module, name)
        assert issubclass(operator, lamp_addon.jobs.ModalJob), name
        assert operator.key() == operator.bl_idname
    # The modal jobs' polling interval is declared once (the viewport preview polls at its own rate).
    declared = [p.relative_to(ADDON).as_posix() for p in ADDON.rglob("*.py")
                if re.search(r"^POLL_SECONDS\s*=", p.read_text(), re.M)]
    assert "jobs.py" in declared
    assert not {"render/ops.py", "compare/ops.py", "study/ops.py", "presets/library.py"} & set(declared)


@pytest.mark.slow
def test_no_import_circle_through_the_study_camera_and_compare_modules():
    graph = package_imports(ADDON)

    def reaches(start: str, goal: str) -> bool:
        seen, todo = set(), [start]
        while todo:
            node = todo.pop()
            for nxt in graph.get(node, ()):
                if nxt == goal:
                    return True
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return False

    for module in ("study.ops", "study.panel", "study.settings", "design.camera", "design.lamp_camera",
                   "design.view_link", "render.ops", "compare.ops", "compare.headless", "jobs"):
        assert not reaches(module, module), module
