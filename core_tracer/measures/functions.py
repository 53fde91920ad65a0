"""The rear signal functions the measures know and the regulations each is measured against (no numpy:
a name check, the page and the table read them without the tracer)."""

from __future__ import annotations

# function -> (UN R148 key, FMVSS 108 key, signal colour)
FUNCTIONS: dict[str, tuple[str, str, str]] = {
    "tail": ("R148 R1", "FMVSS taillamp", "red"),
    "stop": ("R148 S1", "FMVSS stop", "red"),
    "turn": ("R148 2a", "FMVSS rear turn amber", "amber"),
    "reversing": ("R148 AR", "FMVSS backup", "white"),
}
NOTE = ("Simulated figures of a design, for choosing between variants; a homologation laboratory's measurement "
        "of a built lamp decides approval.")
