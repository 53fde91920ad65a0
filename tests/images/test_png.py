"""PNG files written with zlib alone (core_tracer.images.png): read back exactly by OpenImageIO."""

from __future__ import annotations

import numpy as np
import OpenImageIO as oiio

from core_tracer.images.png import write_png


def test_a_png_reads_back_exactly(tmp_path):
    rng = np.random.default_rng(3)
    rgb = rng.integers(0, 256, size=(37, 53, 3), dtype=np.uint8)  # odd sizes: no row padding assumed
    write_png(tmp_path / "page.png", rgb, {"Title": "Measures of a lamp"})
    buf = oiio.ImageBuf(str(tmp_path / "page.png"))
    assert (buf.spec().width, buf.spec().height, buf.spec().nchannels) == (53, 37, 3)
    np.testing.assert_array_equal(buf.get_pixels(oiio.UINT8), rgb)
    assert {a.name: a.value for a in buf.spec().extra_attribs}.get("DocumentName") == "Measures of a lamp"  # PNG Title
    assert [p.name for p in tmp_path.iterdir()] == ["page.png"]  # no temporary file left beside it
