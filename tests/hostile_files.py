"""Generators of hostile files read back by the project (issue 33 item 6): light-states files,
cache cells. Each takes a ``random.Random`` and a good file's bytes and returns (what it is, bytes),
so a campaign of any length is reproducible from its seed."""

from __future__ import annotations

import io
import json
import random
import struct
import zipfile
import zlib

import numpy as np

ZIP_DEFLATED = zipfile.ZIP_DEFLATED


def npy_bytes(array: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    np.lib.format.write_array(buffer, array, allow_pickle=True)
    return buffer.getvalue()


def npy_header(shape: tuple[int, ...], dtype: str = "<f4", fortran: bool = False) -> bytes:
    """An .npy header alone, claiming ``shape`` (its data is whatever follows)."""
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(buffer, {"descr": dtype, "fortran_order": fortran, "shape": shape})
    return buffer.getvalue()


def members(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return {info.filename: z.read(info) for info in z.infolist()}


def npz_of(parts: dict[str, bytes]) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", ZIP_DEFLATED) as z:
        for name, data in parts.items():
            z.writestr(name, data)
    return buffer.getvalue()


def zeros_bomb(name: str, header: bytes, inflated: int, others: dict[str, bytes], claimed: int | None = None) -> bytes:
    """An .npz whose member ``name`` is ``header`` then ``inflated`` zero bytes, deflated by repeating
    one flushed block (1.7 GB of zeros is about 1.7 MB), its zip directory saying ``claimed`` bytes
    (default the truth); its CRC is wrong on purpose: a reader must refuse on sizes before it matters.
    ``others`` are stored beside it."""
    chunk = 1 << 20
    c = zlib.compressobj(9, zlib.DEFLATED, -15)
    head = c.compress(header) + c.compress(bytes(chunk)) + c.flush(zlib.Z_FULL_FLUSH)
    block = c.compress(bytes(chunk)) + c.flush(zlib.Z_FULL_FLUSH)
    count = max(0, inflated // chunk - 1)
    tail = c.compress(bytes(max(0, inflated - chunk * (count + 1)))) + c.flush(zlib.Z_FINISH)
    body, directory = bytearray(), []
    for other, data in others.items():
        local, central = _entry(other, zlib.compress(data)[2:-4], zlib.crc32(data), len(data), len(body))
        body += local
        directory.append(central)
    size = len(header) + inflated if claimed is None else claimed
    local, central = _entry(name, head + block * count + tail, 0, size, len(body))
    body += local
    directory.append(central)
    listing = b"".join(directory)
    return bytes(body) + listing + struct.pack("<4sHHHHIIH", b"PK\x05\x06", 0, 0, len(directory), len(directory),
                                               len(listing), len(body), 0)


def _entry(name: str, compressed: bytes, crc: int, size: int, offset: int) -> tuple[bytes, bytes]:
    encoded = name.encode()
    big = size > 0xFFFFFFFF or len(compressed) > 0xFFFFFFFF
    extra = struct.pack("<HHQQ", 1, 16, size, len(compressed)) if big else b""
    csize, usize = (0xFFFFFFFF, 0xFFFFFFFF) if big else (len(compressed), size)
    local = struct.pack("<4sHHHHHIIIHH", b"PK\x03\x04", 45, 0, 8, 0, 0, crc, csize, usize, len(encoded),
                        len(extra)) + encoded + extra + compressed
    central = struct.pack("<4sHHHHHHIIIHHHHHII", b"PK\x01\x02", 45, 45, 0, 8, 0, 0, crc, csize, usize,
                          len(encoded), len(extra), 0, 0, 0, 0, offset) + encoded + extra
    return local, central


# ---------------------------------------------------------------------------------------------
# Light-states files


def _header_of(parts: dict[str, bytes]) -> dict:
    raw = np.lib.format.read_array(io.BytesIO(parts["header.npy"]))
    return json.loads(raw.tobytes().decode())


def _with_header(parts: dict[str, bytes], header: object) -> dict[str, bytes]:
    text = json.dumps(header).encode() if not isinstance(header, bytes) else header
    return {**parts, "header.npy": npy_bytes(np.frombuffer(text, np.uint8))}


HOSTILE_VALUES = [None, True, -1, 0, 1e308, float("nan"), float("inf"), "x" * 300, [], {}, "\ud800", 10**400,
                  -1e-320, [1, 2], {"a": 1}]


def hostile_states_file(rng: random.Random, good: bytes) -> tuple[str, bytes]:
    """One hostile variant of the good light-states file ``good``."""
    parts = members(good)
    header = _header_of(parts)
    array_names = [n for n in parts if n != "header.npy"]
    kind = rng.choice(["truncate", "flip", "header-field", "scene-field", "state-field", "stats-field",
                       "nan", "inf", "huge", "dtype", "shape", "fortran", "object", "extra", "missing",
                       "header-not-json", "header-dtype", "bomb-claimed", "bomb-lying", "deep-json"])
    if kind == "truncate":
        return kind, good[:rng.randrange(len(good))]
    if kind == "flip":
        data = bytearray(good)
        for _ in range(rng.randint(1, 8)):
            data[rng.randrange(len(data))] ^= 1 << rng.randrange(8)
        return kind, bytes(data)
    if kind == "header-field":
        key = rng.choice(["format", "scene", "stats", "states"])
        return f"{kind}:{key}", npz_of(_with_header(parts, {**header, key: rng.choice(HOSTILE_VALUES)}))
    if kind == "scene-field":
        scene = json.loads(json.dumps(header["scene"]))
        section = rng.choice([k for k, v in scene.items() if isinstance(v, dict)])
        if scene[section]:
            field = rng.choice(list(scene[section]))
            scene[section][field] = rng.choice(HOSTILE_VALUES)
        else:
            field = "?"
        return f"{kind}:{section}.{field}", npz_of(_with_header(parts, {**header, "scene": scene}))
    if kind == "state-field":
        states = json.loads(json.dumps(header["states"]))
        s = rng.choice(states)
        s[rng.choice(list(s))] = rng.choice(HOSTILE_VALUES)
        if rng.random() < 0.3:
            states.append(dict(s))
        return kind, npz_of(_with_header(parts, {**header, "states": states}))
    if kind == "stats-field":
        return kind, npz_of(_with_header(parts, {**header, "stats": {**header["stats"],
                                                                     rng.choice(["light_model", "bands"]):
                                                                     rng.choice(HOSTILE_VALUES + [10**6, 3])}}))
    name = rng.choice(array_names)
    array = np.lib.format.read_array(io.BytesIO(parts[name]))
    if kind in ("nan", "inf", "huge"):
        bad = array.copy()
        value = {"nan": np.nan, "inf": rng.choice([np.inf, -np.inf]), "huge": np.float32(3e38)}[kind]
        bad.flat[rng.randrange(bad.size)] = value
        if kind == "huge":
            bad[...] = value
        return kind, npz_of({**parts, name: npy_bytes(bad)})
    if kind == "dtype":
        return kind, npz_of({**parts, name: npy_bytes(array.astype(rng.choice(["<f8", "<f2", "<i4", ">f4", "u1"])))})
    if kind == "shape":
        h, w, _ = array.shape
        shape = rng.choice([(h, w), (h, w, 4), (w, h, 3), (h + 1, w, 3), (0, w, 3), (1, 1, 3)])
        return kind, npz_of({**parts, name: npy_bytes(np.zeros(shape, np.float32))})
    if kind == "fortran":
        return kind, npz_of({**parts, name: npy_bytes(np.asfortranarray(array))})
    if kind == "object":
        return kind, npz_of({**parts, name: npy_bytes(np.array([{"a": 1}, None], dtype=object))})
    if kind == "extra":
        return kind, npz_of({**parts, rng.choice(["pass_99.npy", "x.txt", "../evil.npy"]): npy_bytes(array)})
    if kind == "missing":
        return kind, npz_of({k: v for k, v in parts.items() if k != name})
    if kind == "header-not-json":
        return kind, npz_of(_with_header(parts, rng.choice([b"\xff\xfe", b"{", b"[" * 100000, b"NaN"])))
    if kind == "header-dtype":
        return kind, npz_of({**parts, "header.npy": npy_bytes(np.zeros(4, np.float64))})
    if kind == "deep-json":
        return kind, npz_of(_with_header(parts, b"[" * 50000 + b"]" * 50000))
    h, w, _ = array.shape
    inflated = rng.choice([17 * 10**8, 4 * 2**30 + 4, 10**8])
    side = max(1, int((inflated // 12) ** 0.5))
    if kind == "bomb-claimed":  # the zip directory says it: refused from the sizes alone
        others = {k: v for k, v in parts.items() if k != name}
        return kind, zeros_bomb(name, npy_header((side, side, 3)), side * side * 12, others)
    # bomb-lying: the npy header and the zip directory claim the scene's size, the data inflates far beyond
    others = {k: v for k, v in parts.items() if k != name}
    header = npy_header((h, w, 3))
    return kind, zeros_bomb(name, header, inflated, others, claimed=len(header) + h * w * 12)


# ---------------------------------------------------------------------------------------------
# Spectra and measured curves


HOSTILE_NUMBERS = ["0", "1", "1e-320", "1e-300", "1.7e308", "1e30", "1e31", "-0", "-1", "nan", "inf", "0.5", "1e-9"]


def hostile_curve(rng: random.Random) -> tuple[str, str]:
    """(what it is, a .csv of nm,value rows) of the kinds a careless or hostile teammate writes."""
    kind = rng.choice(["outside-visible", "one-zero-row", "all-zero", "huge", "tiny", "narrow", "partial",
                       "random", "few", "decreasing", "text"])
    if kind == "outside-visible":
        lo = rng.choice([200.0, 250.0, 790.0, 1000.0])
        rows = [(lo + 5 * i, rng.random()) for i in range(rng.randint(2, 20))]
    elif kind == "one-zero-row":
        rows = [(380.0 + 10 * i, rng.choice([0.9, 0.5, 1.0])) for i in range(41)]
        zero = rng.randrange(len(rows))
        rows[zero] = (rows[zero][0], 0.0)
    elif kind == "all-zero":
        rows = [(380.0, 0.0), (780.0, 0.0)]
    elif kind in ("huge", "tiny"):
        value = float(rng.choice(["1.7e308", "1e300", "1e31"] if kind == "huge" else ["1e-320", "5e-324", "1e-300"]))
        rows = [(380.0 + 100 * i, value) for i in range(5)]
    elif kind == "narrow":
        centre = rng.uniform(375.0, 790.0)
        rows = [(centre - 0.01, 0.0), (centre, 1.0), (centre + 0.01, 0.0)]
    elif kind == "partial":
        lo = rng.uniform(600.0, 779.0)
        rows = [(lo, rng.random()), (lo + 50.0, rng.random())]
    elif kind == "few":
        rows = [(rng.uniform(200.0, 2000.0), rng.random())]
    elif kind == "decreasing":
        rows = [(700.0, 1.0), (500.0, 1.0)]
    elif kind == "text":
        return kind, rng.choice(["nm,value\n", "", "\x00\x01", "380;0.5\n780;0.5\n", "380,0.5,1\n", "a,b\nc,d\n"])
    else:
        rows = sorted({round(rng.uniform(200.0, 2000.0), 3): rng.choice(HOSTILE_NUMBERS) for _ in range(
            rng.randint(2, 30))}.items())
        return kind, "".join(f"{nm},{v}\n" for nm, v in rows)
    return kind, "".join(f"{nm!r},{v!r}\n" for nm, v in rows)


def hostile_bulb(rng: random.Random) -> tuple[str, dict]:
    """(what it is, fields to set on a photometric lamp's bulb section)."""
    kind = rng.choice(["led", "radius", "flux", "named"])
    if kind == "led":
        return kind, {"type": "custom", "spectrum": "led", "flux_lm": rng.choice([1.0, 100.0, 1e5]),
                      "led_peak_nm": rng.choice([360.0, 370.0, 379.0, 781.0, 800.0, 830.0, rng.uniform(360, 830)]),
                      "led_width_nm": rng.choice([0.1, 1.0, 5.0, 100.0, rng.uniform(0.1, 200.0)])}
    if kind == "radius":
        return kind, {"radius": rng.choice([1e-320, 5e-324, 1e-300, 1e-160, 1e-155, 1e-9, 1e-3, 0.5])}
    if kind == "flux":
        return kind, {"type": "custom", "spectrum": rng.choice(["incandescent", "red_led", "white_led"]),
                      "flux_lm": rng.choice([0.0, 1e-300, 1e5, 1e-320]), "radius": rng.choice([1e-3, 1e-150, 8.0])}
    return kind, {"type": rng.choice(["P21/5W", "R5W", "PY21/5W"]), "radius": rng.choice([1e-320, 1e-3, 4.0])}


# ---------------------------------------------------------------------------------------------
# Cache cells


def hostile_cell(rng: random.Random, good: np.ndarray) -> tuple[str, object]:
    """(what it is, the bytes to put where a cell of ``good``'s shape is kept, or "fifo"/"folder"/"link")."""
    kind = rng.choice(["nan", "inf", "shape", "dtype", "object", "huge-header", "truncate", "flip", "fortran",
                       "empty", "fifo", "folder", "link", "huge-values", "negative-shape"])
    h, w, _ = good.shape
    if kind in ("fifo", "folder", "link"):
        return kind, kind
    if kind in ("nan", "inf"):
        bad = good.copy()
        bad.flat[rng.randrange(bad.size)] = np.nan if kind == "nan" else -np.inf
        return kind, npy_bytes(bad)
    if kind == "shape":
        return kind, npy_bytes(np.zeros(rng.choice([(h, w), (w, h, 3), (h, w, 4), (1, 1, 3), (0, w, 3)]), np.float32))
    if kind == "dtype":
        return kind, npy_bytes(good.astype(rng.choice(["<f8", "<f2", "<i4", ">f4", "u1", "<c8"])))
    if kind == "object":
        return kind, npy_bytes(np.array([{"a": 1}], dtype=object))
    if kind == "huge-header":
        return kind, npy_header(rng.choice([(100000, 100000, 3), (2**40, 1, 3), (h, w, 3 * 10**9)])) + bytes(64)
    if kind == "negative-shape":
        return kind, npy_header((h, w, 3)).replace(f"({h}, {w}, 3)".encode(), f"(-{h}, {w}, 3)".encode()) + bytes(64)
    if kind == "truncate":
        data = npy_bytes(good)
        return kind, data[:rng.randrange(len(data))]
    if kind == "flip":
        data = bytearray(npy_bytes(good))
        for _ in range(rng.randint(1, 6)):
            data[rng.randrange(min(len(data), 128))] ^= 1 << rng.randrange(8)
        return kind, bytes(data)
    if kind == "fortran":
        return kind, npy_bytes(np.asfortranarray(good))
    if kind == "huge-values":
        return kind, npy_bytes(np.full(good.shape, 3e38, np.float32))
    return kind, b""


# ---------------------------------------------------------------------------------------------
# Optimise files, study and scheduler flags


HOSTILE_STORAGE = ["sqlite:////etc/passwd", "sqlite:///../x.db", "sqlite:///~/x.db", "sqlite://", "sqlite:///",
                   "sqlite:///file:x.db?mode=rwc&uri=true", "file:///tmp/x.db", "sqlite:///x.db?timeout=1",
                   "sqlite:///" + "a" * 5000 + ".db", "sqlite:///\x00.db", "sqlite:///\ud800.db", "postgresql://",
                   "oracle://u@h/d", "sqlite:////dev/zero", "sqlite:///.", "sqlite:///sub/../../x.db", 1, None,
                   [], {"a": 1}, "", "://", "sqlite:///%2e%2e/x.db", "sqlite:///db\nname.db", "mysql+bad://x"]
HOSTILE_BASES = ["/etc/passwd", "~/x.json", "../x.json", "a/../../x.json", "/dev/zero", ".", "", "\x00",
                 "x" * 5000, "\ud800.json", 1, None, [], {"lamps": "x"}, True, "sub/../base.json"]


def hostile_optimise_doc(rng: random.Random, good: dict) -> tuple[str, dict]:
    """One mutation of a good ``lamp-optimise/1`` document."""
    doc = json.loads(json.dumps(good))
    kind = rng.choice(["storage", "base", "step", "range", "values", "parameter", "name", "trials", "size",
                       "parallel", "objective", "unknown"])
    if kind == "storage":
        doc["storage"] = rng.choice(HOSTILE_STORAGE)
    elif kind == "base":
        doc["base"] = rng.choice(HOSTILE_BASES)
    elif kind == "step":
        doc["parameters"][0]["step"] = rng.choice([1e-300, 5e-324, -1.0, 0.0, float("nan"), 1e308, "1", None, 2.0])
    elif kind == "range":
        doc["parameters"][0]["range"] = rng.choice([[0.0, 1e308], [float("nan"), 1.0], [1.0, 1.0], [2, 1], [1], "x",
                                                    [None, 1.0], [-1e308, 1e308], [0.5, float("inf")]])
    elif kind == "values":
        doc["parameters"][0] = {"parameter": "cuts.height", "values": rng.choice(
            [[], [1e308], [float("nan")], list(range(100000)), ["x"], [[1]], None, [0.5] * 3])}
    elif kind == "parameter":
        doc["parameters"][0]["parameter"] = rng.choice(["", "lamps[9999].lens.ior", "__class__", "cuts.height[0]",
                                                       "x" * 10000, None, "bulb.offset", "\ud800"])
    elif kind == "name":
        doc["name"] = rng.choice(["", "a" * 201, "\x1b[31mred", "\ud800", 1, None, "name\nwith newline"])
    elif kind == "trials":
        doc["trials"] = rng.choice([0, -1, 10**400, 1e308, "5", None, 10001, True])
    elif kind == "size":
        doc["size"] = rng.choice([[0, 0], [10**9, 1], "x", [16], [16.5, 16], None, [-1, 16]])
    elif kind == "parallel":
        doc["parallel"] = rng.choice([0, 10**6, -1, "2", 1e308])
    elif kind == "objective":
        doc["objectives"] = rng.choice([[], [{"measure": "ssim", "reference": "/etc/passwd"}],
                                        [{"measure": "ssim", "reference": "../x.exr"}], [{"measure": None}],
                                        "x", [{"measure": "lens_luminance", "goal": "up"}]])
    else:
        doc[rng.choice(["__proto__", "\ud800", "x" * 300, ""])] = 1
    return kind, doc


def hostile_study_flags(rng: random.Random) -> tuple[str, list[str], dict[str, str]]:
    """(what it is, extra command-line arguments for ``study``, extra environment)."""
    kind = rng.choice(["scheduler", "env", "workers", "size", "engine", "cache"])
    printable = "".join(chr(rng.randrange(32, 127)) for _ in range(rng.randint(0, 40)))
    addresses = ["tcp://", "tcp://host:99999", "tcp://[::1", ":::", "tcp://h\x01:1", "inproc://x", "x" * 300,
                 "tcp://host:port", "ws://host:1", "tcp://256.1.1.1:80", "tcp://-x-:1", printable, "local",
                 "tcp://127.0.0.1:0", "tls://:1", "tcp://user:pw@h:1", "tcp://h:1/x?y#z"]
    if kind == "scheduler":
        return kind, ["--scheduler", rng.choice(addresses)], {}
    if kind == "env":
        return kind, ["--engine", "dask"], {"DASK_SCHEDULER_ADDRESS": rng.choice(addresses).replace("\x00", "")}
    if kind == "workers":
        return kind, ["--workers", rng.choice(["100000", "-1", "2" * 30, "0", "x", "1e3", "7", "4096"])], {}
    if kind == "size":
        return kind, ["--size", rng.choice(["0x0", "100000x100000", "x", "16x16x16", "-16x16", "16", "1e9x1"])], {}
    if kind == "engine":
        return kind, ["--engine", rng.choice(["dask", "processes", "threads", "", "\x00"]).replace("\x00", "?")], {}
    return kind, ["--cache", rng.choice(["/dev/null", "/proc/self", "\udcff", ".", "x" * 5000])], {}


def spectrum_scene_file(folder, bulb: dict | None = None, lens_curve: str | None = None,
                        bulb_curve: str | None = None):
    """A 12 x 8 px photometric stop lamp in ``folder``, its bulb edited, with a measured filter or bulb curve."""
    from helpers import PRESETS

    doc = json.loads((PRESETS / "photometric-stop-lamp.json").read_text())
    doc["image"].update(width=12, height=8, samples=1)
    doc["lamps"][0]["bulb"].update(bulb or {})
    if lens_curve is not None:
        doc["lamps"][0]["lens"].update(filter="file", filter_file="filter.csv")
        (folder / "filter.csv").write_text(lens_curve)
    if bulb_curve is not None:
        doc["lamps"][0]["bulb"].update(type="custom", spectrum="file", spectrum_file="bulb.csv", flux_lm=100.0)
        (folder / "bulb.csv").write_text(bulb_curve)
    path = folder / "scene.json"
    path.write_text(json.dumps(doc))
    return path


def refused_or_renders(path) -> str:
    """'refused' (a one-line ``SceneError`` naming a field of lamps[0], as ``validate`` says it) or
    'rendered' (a finite image); anything else fails the caller's test."""
    from core_tracer.cli.common import load_scene_file
    from core_tracer.raytrace.engine import render_passes
    from core_tracer.scene.beside import with_spectrum_files
    from core_tracer.scene.reading import SceneError

    try:
        scene = load_scene_file(path)
    except SceneError as e:
        assert "\n" not in str(e) and "lamps[0]" in e.path, str(e)
        return "refused"
    image = render_passes(with_spectrum_files(path, scene), keep_passes=False).image
    assert np.isfinite(image).all(), path.read_text()[:300]
    return "rendered"
