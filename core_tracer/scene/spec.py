"""The field declarations of a ``lamp-scene/1`` document.

Every parameter of a lamp design is declared here once, with its unit, allowed range, default
and description. The validator (``scene.py``), the README's field table, the JSON presets and
the Blender properties (``lamp_addon/properties.py``) all follow from these declarations.

Lengths are millimetres, absorption coefficients per millimetre, angles degrees, colours
linear RGB (MODEL.md §2).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

SCHEMA = "lamp-scene/1"
MAX_LAMPS = 4
MAX_IMAGE_SIDE = 8192
# A direction vector shorter than this cannot be normalised reliably (its square underflows).
MIN_DIRECTION_LENGTH = 1e-9
# mm: the camera must stand at least this far from its target to have a view direction.
MIN_CAMERA_DISTANCE = 1e-6
# At most this many cuts across the lens diameter: the cut cell walk then crosses a bounded
# number of cells (about sqrt 2 times this) and its cell arithmetic stays exact.
MAX_CUTS_ACROSS = 1000


@dataclass(frozen=True)
class Num:
    """A number, or a fixed-size vector of numbers (``size`` > 1)."""

    default: float | tuple[float, ...] | None
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    doc: str = ""
    size: int = 1
    integer: bool = False
    nonzero: bool = False  # a direction: length at least MIN_DIRECTION_LENGTH
    subtype: str = ""  # a hint for user interfaces: "color", "distance", "direction", "xyz"

    def range_text(self) -> str:
        """The allowed range as the error messages and the README print it."""
        left = "(" if self.lo_open else "["
        right = ")" if self.hi_open else "]"
        lo = "-inf" if self.lo is None else _fmt(self.lo)
        hi = "inf" if self.hi is None else _fmt(self.hi)
        if self.lo is None and self.hi is None:
            text = "any finite number"
        else:
            text = f"{left}{lo}, {hi}{right}"
        if self.unit:
            text += f" {self.unit}"
        if self.size > 1:
            text = f"{self.size} numbers, each {text}"
        if self.nonzero:
            text += f", length at least {_fmt(MIN_DIRECTION_LENGTH)}"
        return text

    def too_short(self, items: list[float]) -> bool:
        """Whether a direction vector is too short to normalise (only for ``nonzero`` fields)."""
        return self.nonzero and math.fsum(x * x for x in items) < MIN_DIRECTION_LENGTH**2


@dataclass(frozen=True)
class Choice:
    default: str
    choices: tuple[str, ...]
    doc: str = ""

    def range_text(self) -> str:
        return "one of " + ", ".join(f'"{c}"' for c in self.choices)


@dataclass(frozen=True)
class Text:
    default: str
    doc: str = ""
    max_len: int = 200

    def range_text(self) -> str:
        return f"a string of at most {self.max_len} characters"


@dataclass(frozen=True)
class Tags:
    doc: str = ""
    max_items: int = 32
    max_len: int = 40

    @property
    def default(self) -> list[str]:
        return []

    def range_text(self) -> str:
        return f"a list of at most {self.max_items} strings of at most {self.max_len} characters"


@dataclass(frozen=True)
class Flag:
    default: bool
    doc: str = ""

    def range_text(self) -> str:
        return "true or false"


@dataclass(frozen=True)
class Section:
    fields: dict[str, Spec]
    doc: str = ""
    optional: tuple[str, ...] = ()  # keys that have no default and may be absent


@dataclass(frozen=True)
class ListOf:
    item: Section
    min_items: int
    max_items: int
    doc: str = ""

    def range_text(self) -> str:
        return f"a list of {self.min_items} to {self.max_items} items"


Spec = Num | Choice | Text | Tags | Flag | Section | ListOf


def _fmt(x: float) -> str:
    return f"{x:g}"


def _color(default, doc, hi=1.0) -> Num:
    return Num(tuple(default), 0.0, hi, unit="", doc=doc, size=3, subtype="color")


def _length(default, doc, lo=0.0, hi=10000.0, lo_open=True) -> Num:
    return Num(default, lo, hi, lo_open=lo_open, unit="mm", doc=doc, subtype="distance")


def _position(default, doc, size=3) -> Num:
    return Num(tuple(default), -1.0e5, 1.0e5, unit="mm", doc=doc, size=size, subtype="xyz")


CAMERA = Section(
    {
        "type": Choice("perspective", ("perspective", "orthographic"), "Projection of the camera"),
        "position": _position((0, -800, 0), "Eye position (the lamp faces -Y, so y < 0)"),
        "target": _position((0, 0, 0), "Point the camera looks at"),
        "up": Num((0, 0, 1), -1.0, 1.0, doc="Up direction of the image", size=3, nonzero=True,
                  subtype="direction"),
        "fov_deg": Num(16.0, 0.1, 170.0, unit="deg",
                       doc="Perspective: full field of view across the fitted image side"),
        "width": _length(250.0, "Orthographic: width of the view across the fitted image side",
                         hi=1.0e5),
        "sensor_fit": Choice("auto", ("auto", "horizontal", "vertical"),
                             "Which image side the field of view spans (auto: the larger, as Blender)"),
        "shift": Num((0.0, 0.0), -2.0, 2.0, doc="Lens shift in fractions of the fitted side (as Blender)",
                     size=2),
    },
    "The view of the tracer (and of Blender's scene camera); defaults frame the body",
)

IMAGE = Section(
    {
        "width": Num(512, 1, MAX_IMAGE_SIDE, unit="px", doc="Image width in pixels", integer=True),
        "height": Num(512, 1, MAX_IMAGE_SIDE, unit="px", doc="Image height in pixels", integer=True),
    },
    "Image size",
)

LIGHT = Section(
    {
        "direction": Num((0.3, -1.0, 0.6), -1.0e3, 1.0e3, size=3, nonzero=True, subtype="direction",
                         doc="Direction from the lamp toward the light (eq. 1)"),
        "color": _color((1, 1, 1), "Light colour: the specular colour R1G1B1 of eq. 1", hi=1000.0),
        "ambient": Num(0.25, 0.0, 1.0, doc="Ambient fraction d of eq. 1"),
    },
    "The directional light of equation (1)",
)

BODY = Section(
    {
        "center": _position((0, 0), "Centre [x, z] of the front face in the plane y = 0", size=2),
        "size": Num((220.0, 120.0), 0.0, 1.0e4, lo_open=True, unit="mm", size=2, subtype="xyz",
                    doc="Width (x) and height (z) of the front face"),
        "depth": _length(80.0, "Depth of the box into +y"),
        "color": _color((0.6, 0.6, 0.62), "Diffuse colour R0G0B0 of the body (eq. 1)"),
        "specular": Num(0.5, 0.0, 1.0, doc="Specular reflectance w of the body (eq. 1)"),
        "shininess": Num(30.0, 0.0, 1.0e4, doc="Specular spread n of the body (eq. 1)"),
    },
    "The opaque box that holds the lamps",
)

LENS = Section(
    {
        "radius": _length(45.0, "Lens radius R", hi=1000.0),
        "thickness": _length(3.0, "Lens thickness t: outer face y = 0, base of the cuts y = t", hi=100.0),
        "ior": Num(1.49, 1.0, 3.0, doc="Refractive index n of the lens"),
        "absorption": Num((0.02, 1.5, 1.6), 0.0, 100.0, unit="1/mm", size=3,
                          doc="RGB absorption coefficients A (eq. 2)"),
        "transmitted_color": Num((0.9, 0.05, 0.05), 0.0, 1.0, lo_open=True, size=3, subtype="color",
                                 doc="Colour seen through reference_thickness of lens "
                                     "(instead of absorption)"),
        "reference_thickness": _length(3.0, "Thickness at which transmitted_color is seen", hi=100.0),
        "diffuse_color": _color((0.05, 0.0, 0.0), "Diffuse colour of the lens surface (eq. 1)"),
        "specular": Num(0.8, 0.0, 1.0, doc="Specular reflectance w of the lens surface (eq. 1)"),
        "shininess": Num(60.0, 0.0, 1.0e4, doc="Specular spread n of the lens surface (eq. 1)"),
        "side_wall_color": _color((0.05, 0.02, 0.02), "Colour of the opaque lens side wall"),
    },
    "The lens disk; its colour is given by absorption, or by transmitted_color at "
    "reference_thickness (never both)",
    optional=("absorption", "transmitted_color", "reference_thickness"),
)

CUTS = Section(
    {
        "pitch": _length(9.0, "Cut size p: side of the square lenslet cells", hi=1000.0),
        "height": Num(1.5, 0.0, 100.0, unit="mm",
                      doc="Cut height h (sag of each spherical lenslet); 0 is a flat inner face",
                      subtype="distance"),
    },
    "Fish-eye (spherical) cuts on the inner face of the lens",
)

REFLECTOR = Section(
    {
        "focal_length": _length(18.0, "Focal length f of the paraboloid", hi=1000.0),
        "gap": Num(0.0, 0.0, 1000.0, unit="mm", subtype="distance",
                   doc="Gap between the cut apex plane and the reflector rim"),
        "color": _color((0.3, 0.3, 0.3), "Constant colour seen on the first reflector hit"),
        "reflectance": Num(0.8, 0.0, 1.0, doc="Specular (mirror) reflectance of the reflector"),
        "scatter": Num(0.8, 0.0, 1.0, doc="Scatter reflectance w of the Blinn term (eq. 3)"),
        "shininess": Num(20.0, 0.0, 1.0e4, doc="Scatter spread n of the Blinn term (eq. 3)"),
    },
    "The paraboloid reflector behind the lens",
)

BULB = Section(
    {
        "radius": _length(8.0, "Bulb radius", hi=1000.0),
        "offset": Num((0.0, 0.0, 0.0), -1000.0, 1000.0, unit="mm", size=3, subtype="xyz",
                      doc="Bulb centre relative to the reflector focus [x, y, z]"),
        "intensity": _color((8.0, 7.0, 6.0), "Bulb intensity I0 (RGB)", hi=1.0e4),
        "on": Flag(True, "Whether the bulb is lit"),
    },
    "The spherical bulb, the light source",
)

SOCKET = Section(
    {
        "radius": _length(5.0, "Socket radius", hi=1000.0),
        "color": _color((0.1, 0.1, 0.1), "Socket colour"),
    },
    "The cylindrical socket from the reflector vertex to the bulb centre",
)

LAMP = Section(
    {
        "center": _position((0, 0), "Centre [x, z] of the lens in the plane y = 0", size=2),
        "lens": LENS,
        "cuts": CUTS,
        "reflector": REFLECTOR,
        "bulb": BULB,
        "socket": SOCKET,
    },
    "One lamp: lens, cuts, reflector, bulb and socket",
)

SCENE = Section(
    {
        "schema": Choice(SCHEMA, (SCHEMA,), "Format and version of the document"),
        "name": Text("Untitled lamp", "Name of the design"),
        "author": Text("", "Who made the design"),
        "description": Text("", "Free text", max_len=2000),
        "tags": Tags("Keywords for finding the design"),
        "camera": CAMERA,
        "image": IMAGE,
        "light": LIGHT,
        "background": _color((0, 0, 0), "Colour of rays that leave the scene (0 in the paper)"),
        "body": BODY,
        "lamps": ListOf(LAMP, 1, MAX_LAMPS, "The lamps, 1 to 4"),
    },
    "A lamp-scene/1 document",
    optional=("camera",),
)


@dataclass(frozen=True)
class FieldInfo:
    """One leaf field with its dotted path, for tables and property generation."""

    path: str
    spec: Spec


def iter_fields(section: Section = SCENE, prefix: str = "") -> Iterator[FieldInfo]:
    """Every leaf field below ``section``, depth first, lamps as ``lamps[].…``."""
    for key, spec in section.fields.items():
        path = f"{prefix}{key}"
        if isinstance(spec, Section):
            yield from iter_fields(spec, path + ".")
        elif isinstance(spec, ListOf):
            yield from iter_fields(spec.item, path + "[].")
        else:
            yield FieldInfo(path, spec)


def lookup(path: str) -> Spec:
    """The spec of a dotted path such as ``lamps[].lens.ior`` or ``lens.ior`` (lamp-relative)."""
    node: Spec = SCENE
    parts = path.replace("[]", "").split(".")
    if parts[0] in LAMP.fields and parts[0] not in SCENE.fields:
        node = LAMP
    for part in parts:
        if isinstance(node, ListOf):
            node = node.item
        if not isinstance(node, Section) or part not in node.fields:
            raise KeyError(path)
        node = node.fields[part]
    return node
