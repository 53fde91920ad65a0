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
