"""How much memory a render or a study needs, estimated before it starts, and the budget it must fit.

The figures are what this program holds at its peak, measured (``benchmarks/bench_memory.py``):
the image and, with ``--passes``, the eight contribution passes as float32 RGB; the copy a file
writer makes; the tracer's bands, which are bounded whatever the image size; and a study's
variant images and its contact sheet. A request above ``MEMORY_BUDGET`` is refused before any
work starts, with the estimate and the budget in the message (README, "Memory and time").
"""

from __future__ import annotations

from .scene.reading import SceneError

MEMORY_BUDGET = 4 * 2**30  # bytes; README "Memory and time"
BASE_BYTES = 160 * 2**20  # the interpreter, numpy and OpenImageIO loaded, the tracer's bands in flight
RGB_BYTES = 3 * 4  # float32 RGB per pixel
PASS_COUNT = 8
# A study's sheet is held up to four times while it is composed (OpenImageIO's buffer, its copy to
# numpy, a writable copy, the writer's copy); the variant images stay in memory until then.
SHEET_COPIES = 4
# The glare's peak (images/glare.py): float64 and complex128 arrays of the padded 2H x 2W size.
GLARE_BYTES_PER_PIXEL = 300  # measured 280 (tracemalloc, 512² and 1024²)
# A study renders at most this many pixels in all, the pixels of one 4096 x 4096 image: 64
# variants of 512 x 512, or 4 of 2048 x 2048 (an hour or so of CPU time at most, README).
MAX_STUDY_PIXELS = 4096 * 4096
# Samples per pixel cost time, not memory (the tracer's bands hold a bounded number of rays,
# whatever the samples): a render traces at most this many eye rays, those of an 8192 x 8192
# image at 16 samples or a 4096 x 4096 one at 64 (about a quarter of an hour on two cores,
# benchmarks/bench_tracer.py). A 4096 x 4096 image at 256 samples, four times that, is refused.
MAX_EYE_RAYS = 2**30


def gib(n: int) -> str:
    return f"{n / 2**30:.1f} GB"


def render_bytes(width: int, height: int, passes: bool, file_format: str, glare: bool = False) -> int:
    """Peak bytes of ``render``: the image, the passes if kept, the file writer's copy, and the
    glare's FFT arrays if it is on (``images.glare.BYTES_PER_PIXEL``)."""
    pixels = width * height
    image = pixels * RGB_BYTES
    kept = pixels * RGB_BYTES * PASS_COUNT if passes else 0
    # EXR: a float32 copy; PNG: the 8-bit codes and OpenImageIO's copy of them
    writer = pixels * RGB_BYTES if file_format == "exr" else pixels * 3 * 2
    spread = pixels * GLARE_BYTES_PER_PIXEL if glare else 0
    return BASE_BYTES + image + kept + max(writer, spread)  # the glare is done before the file is written


def check_rays(width: int, height: int, samples: int, where: str = "image.samples") -> None:
    """A render traces at most ``MAX_EYE_RAYS`` eye rays: pixels times samples per pixel."""
    rays = width * height * samples
    if rays > MAX_EYE_RAYS:
        most = max(1, MAX_EYE_RAYS // (width * height))
        raise SceneError(where, f"{width}x{height} px at {samples} samples are {rays:,} eye rays; allowed at most "
                                f"{MAX_EYE_RAYS:,} in one render (here 1 to {most} samples, or a smaller image)")


def check_render(width: int, height: int, passes: bool, file_format: str, what: str = "the render",
                 glare: bool = False, samples: int = 1) -> None:
    check_rays(width, height, samples)
    need = render_bytes(width, height, passes, file_format, glare)
    if need > MEMORY_BUDGET:
        hint = " without --passes, or" if passes else ""
        hint += " without glare, or" if glare else ""
        raise SceneError("image", f"{width}x{height} px{' with --passes' if passes else ''}: {what} needs about "
                         f"{gib(need)} of memory; allowed at most {gib(MEMORY_BUDGET)} (render{hint} smaller)")


def check_study_rays(size: tuple[int, int], samples: list[int], where: str = "image.samples") -> None:
    """A study's variants trace at most ``MAX_EYE_RAYS`` eye rays in all, as one render."""
    w, h = size
    rays = w * h * sum(samples)
    if rays > MAX_EYE_RAYS:
        raise SceneError(where, f"{len(samples)} variants of {w}x{h} px at {min(samples)} to {max(samples)} samples "
                                f"are {rays:,} eye rays; allowed at most {MAX_EYE_RAYS:,} in one study (fewer "
                                "samples, smaller variants or fewer of them)")


def study_bytes(variant_pixels: int, count: int, sheet_pixels: int) -> int:
    return BASE_BYTES + variant_pixels * count * RGB_BYTES + sheet_pixels * RGB_BYTES * SHEET_COPIES


def check_study_pixels(size: tuple[int, int], count: int, where: str = "size") -> None:
    """A study renders at most ``MAX_STUDY_PIXELS`` pixels in all."""
    w, h = size
    total = w * h * count
    if total > MAX_STUDY_PIXELS:
        largest = int((MAX_STUDY_PIXELS // count) ** 0.5)
        raise SceneError(where, f"{count} variants of {w}x{h} px are {total:,} pixels; allowed at most "
                                f"{MAX_STUDY_PIXELS:,} in one study (here at most {largest}x{largest} px each, "
                                "or fewer variants)")


def check_study(size: tuple[int, int], count: int, sheet_size: tuple[int, int], where: str = "size") -> None:
    """A study must stay within ``MAX_STUDY_PIXELS`` rendered pixels and the memory budget."""
    check_study_pixels(size, count, where)
    w, h = size
    need = study_bytes(w * h, count, sheet_size[0] * sheet_size[1])
    if need > MEMORY_BUDGET:
        raise SceneError(where, f"the study needs about {gib(need)} of memory; allowed at most "
                                f"{gib(MEMORY_BUDGET)} (smaller variants or fewer of them)")
