"""How much memory a render or a study needs, estimated before it starts, and the budget it must fit.

The figures are what this program holds at its peak, measured (``benchmarks/bench_memory.py``):
the image and, with ``--passes``, the eight contribution passes as float32 RGB; the copy a file
writer makes; the tracer's bands, which are bounded whatever the image size; the world of an
environment image (``raytrace.world_image.peak_bytes``, from its header, before any pixel is read);
the band pool's worker processes, each counted whole, when a render is heavy enough to use them;
and a study's variant images and its contact sheet. A request above ``MEMORY_BUDGET`` is refused
before any work starts, with the estimate and the budget in the message (docs/user-guide.md, "Memory and time").
"""

from __future__ import annotations

from .scene.reading import SceneError

MEMORY_BUDGET = 4 * 2**30  # bytes; docs/user-guide.md "Memory and time"
BASE_BYTES = 160 * 2**20  # the interpreter, numpy and OpenImageIO loaded, the tracer's bands in flight
RGB_BYTES = 3 * 4  # float32 RGB per pixel
PASS_COUNT = 8
# A study's sheet is held up to four times while it is composed (OpenImageIO's buffer, its copy to
# numpy, a writable copy, the writer's copy); the variant images stay in memory until then.
SHEET_COPIES = 4
# The glare's peak (images/glare.py): float64 and complex128 arrays of the padded 2H x 2W size.
GLARE_BYTES_PER_PIXEL = 300  # measured 280 (tracemalloc, 512² and 1024²)
# A render of at least this many eye rays (pixels x samples) traces its bands in the band pool's
# worker processes (``raytrace.band_pool``); a lighter one is done before they would be up.
POOL_RAYS = 2_000_000
# One band worker at its peak, counted for every worker besides the parent: the interpreter, numpy
# and the tracer (about 60 MB), its bands in flight, and the freed memory its allocator keeps
# mapped (up to 512 MB, ``processes._KEEP_FREED_MEMORY``). Measured with the day preset at 16
# samples (RSS from /proc, tests/raytrace/test_world_memory.py): 201-245 MB a worker at 512², 300-339
# MB at 1024², about 460 MB at 2048²; the environment image's world is mapped from one file that
# every process shares (``raytrace.world_cache``) and is counted once.
WORKER_BYTES = 640 * 2**20
# A study renders at most this many pixels in all, the pixels of one 4096 x 4096 image: 64
# variants of 512 x 512, or 4 of 2048 x 2048 (an hour or so of CPU time at most, docs/user-guide.md).
MAX_STUDY_PIXELS = 4096 * 4096
# Samples per pixel cost time, not memory (the tracer's bands hold a bounded number of rays,
# whatever the samples): a render traces at most this many eye rays, those of an 8192 x 8192
# image at 16 samples or a 4096 x 4096 one at 64 (about a quarter of an hour on two cores,
# benchmarks/bench_tracer.py). A 4096 x 4096 image at 256 samples, four times that, is refused.
MAX_EYE_RAYS = 2**30


def gib(n: int) -> str:
    return f"{n / 2**30:.1f} GB"


def uses_pool(width: int, height: int, samples: int) -> bool:
    """Whether a render of this size traces its bands in the band pool's worker processes."""
    return width * height * samples >= POOL_RAYS


def render_bytes(width: int, height: int, passes: bool, file_format: str, glare: bool = False,
                 environment: int = 0, workers: int = 0) -> int:
    """Peak bytes of ``render``, its worker processes included: the image, the passes if kept, the
    file writer's copy, the glare's FFT arrays if it is on (``images.glare.BYTES_PER_PIXEL``), the
    environment's world (``environment`` bytes) and ``workers`` band workers."""
    pixels = width * height
    image = pixels * RGB_BYTES
    kept = pixels * RGB_BYTES * PASS_COUNT if passes else 0
    # EXR: a float32 copy; PNG: the 8-bit codes and OpenImageIO's copy of them
    writer = pixels * RGB_BYTES if file_format == "exr" else pixels * 3 * 2
    spread = pixels * GLARE_BYTES_PER_PIXEL if glare else 0
    parent = BASE_BYTES + image + kept + max(writer, spread)  # the glare is done before the file is written
    return parent + environment + workers * WORKER_BYTES


def check_rays(width: int, height: int, samples: int, where: str = "image.samples") -> None:
    """A render traces at most ``MAX_EYE_RAYS`` eye rays: pixels times samples per pixel."""
    rays = width * height * samples
    if rays > MAX_EYE_RAYS:
        most = max(1, MAX_EYE_RAYS // (width * height))
        raise SceneError(where, f"{width}x{height} px at {samples} samples are {rays:,} eye rays; allowed at most "
                                f"{MAX_EYE_RAYS:,} in one render (here 1 to {most} samples, or a smaller image)")


def check_render(width: int, height: int, passes: bool, file_format: str, what: str = "the render",
                 glare: bool = False, samples: int = 1, environment: int = 0, workers: int = 0) -> None:
    """Refuse a render above ``MAX_EYE_RAYS`` or whose whole footprint (``render_bytes``: the
    environment's ``environment`` bytes and ``workers`` worker processes included) is above
    ``MEMORY_BUDGET``."""
    check_rays(width, height, samples)
    need = render_bytes(width, height, passes, file_format, glare, environment, workers)
    if need > MEMORY_BUDGET:
        hint = " without --passes, or" if passes else ""
        hint += " without glare, or" if glare else ""
        hint += " with a smaller environment image, or" if environment > need // 4 else ""
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


def pool_workers(width: int, height: int, samples: int, passes: bool, file_format: str, glare: bool = False,
                 environment: int = 0, workers: int = 0) -> int:
    """How many band workers a render uses within the budget: ``workers`` (the pool's size) when it
    is heavy enough for the pool and the whole footprint fits, else 0 (the render runs on threads)."""
    if not uses_pool(width, height, samples):
        return 0
    fits = render_bytes(width, height, passes, file_format, glare, environment, workers) <= MEMORY_BUDGET
    return workers if fits else 0


def study_bytes(variant_pixels: int, count: int, sheet_pixels: int, environment: int = 0) -> int:
    return (BASE_BYTES + environment + variant_pixels * count * RGB_BYTES
            + sheet_pixels * RGB_BYTES * SHEET_COPIES)


def check_study_pixels(size: tuple[int, int], count: int, where: str = "size") -> None:
    """A study renders at most ``MAX_STUDY_PIXELS`` pixels in all."""
    w, h = size
    total = w * h * count
    if total > MAX_STUDY_PIXELS:
        largest = int((MAX_STUDY_PIXELS // count) ** 0.5)
        raise SceneError(where, f"{count} variants of {w}x{h} px are {total:,} pixels; allowed at most "
                                f"{MAX_STUDY_PIXELS:,} in one study (here at most {largest}x{largest} px each, "
                                "or fewer variants)")


def check_study(size: tuple[int, int], count: int, sheet_size: tuple[int, int], where: str = "size",
                environment: int = 0) -> None:
    """A study must stay within ``MAX_STUDY_PIXELS`` rendered pixels and the memory budget (its
    largest environment world, ``environment`` bytes, included)."""
    check_study_pixels(size, count, where)
    w, h = size
    need = study_bytes(w * h, count, sheet_size[0] * sheet_size[1], environment)
    if need > MEMORY_BUDGET:
        raise SceneError(where, f"the study needs about {gib(need)} of memory; allowed at most "
                                f"{gib(MEMORY_BUDGET)} (smaller variants or fewer of them)")


# ``measure``: its peak is the largest measuring view's, about 830 bytes a pixel of it (tracemalloc
# over ``measures.report.measure`` of photometric-stop-lamp: 826 at 462 x 262 px, 839 at 232 x 132;
# the float64 XYZ, the lamp of each pixel's points, the luminance, its blur and the kept front view);
# rounded up. Its views are rendered one at a time, on threads.
MEASURE_BYTES_PER_PIXEL = 1024


def measure_bytes(view_pixels: int) -> int:
    """Peak bytes of ``measure`` whose largest view has ``view_pixels`` pixels."""
    return BASE_BYTES + view_pixels * MEASURE_BYTES_PER_PIXEL


def check_measure(width: int, height: int, where: str = "--pixel-mm") -> None:
    """Refuse a ``measure`` whose largest view (``width`` x ``height`` px) is past ``MEMORY_BUDGET``."""
    need = measure_bytes(width * height)
    if need > MEMORY_BUDGET:
        raise SceneError(where, f"the largest measuring view is {width}x{height} px, which needs about {gib(need)} "
                                f"of memory; allowed at most {gib(MEMORY_BUDGET)} (larger pixels)")


def states_bytes(width: int, height: int, states: int, file_format: str = "exr", workers: int = 0,
                 environment: int = 0, sources: int = 0) -> int:
    """Peak bytes of ``states``: one render at a time (``render_bytes``, no passes, no glare) with
    the image of each of ``sources`` kept (a parametric design's one walk: the surroundings and one
    per lamp, ``rays.BySource``; 0: a free-form design's render per state), the surroundings and
    ``states`` passes kept, a temporary of one, and the file's bytes in memory before they are written
    (at most the arrays' size: deflate does not grow them much)."""
    kept = (states + 1) * width * height * RGB_BYTES
    one = render_bytes(width, height, False, file_format, False, environment, workers)
    return one + sources * width * height * RGB_BYTES + 2 * kept + width * height * RGB_BYTES


def check_states(width: int, height: int, samples: int, states: int, workers: int = 0, environment: int = 0,
                 sources: int = 0) -> None:
    """Refuse a ``states`` run past ``MAX_EYE_RAYS`` (one walk's; a render per state: all of theirs
    together) or ``MEMORY_BUDGET`` (``states_bytes``)."""
    check_rays(width, height, samples if sources else samples * (states + 1))
    need = states_bytes(width, height, states, "exr", workers, environment, sources)
    if need > MEMORY_BUDGET:
        raise SceneError("image", f"{width}x{height} px with {states} states and the surroundings: states needs about "
                                  f"{gib(need)} of memory; allowed at most {gib(MEMORY_BUDGET)} (render smaller)")
