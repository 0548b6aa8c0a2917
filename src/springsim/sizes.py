"""How much a scene will take, known before anything is built: particles, springs, bytes.

A scene that asks for more than the machine holds (``particles_per_edge = 2000`` is 8e9
particles) is refused with one line before a single array is allocated. Each body kind says its
own counts (``counts()`` on the body spec: particles and springs, from its parameters alone); a
kind that does not is left out of the estimate. The bytes per particle and per spring bound the
measured peak of building and stepping a cube from above (``benchmarks/model_memory.py``
prints both, for every integrator).
"""
import os

from .errors import require

BYTES_PER_PARTICLE = 1000   # state, model arrays, stage buffers, contact memory
BYTES_PER_SPRING = 400      # pairs, rest lengths, runs, and implicit_euler's Jacobian blocks
MODEL_MEMORY_SHARE = 0.75   # of the machine's memory, for the model and its integrator
MAX_PARTICLES = 2 ** 31 - 1  # particle numbers are 32-bit in the kernels


def machine_memory() -> int | None:
    """The machine's physical memory in bytes (None where the system cannot tell)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemTotal:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def gigabytes(count: float) -> str:
    return f"{count / 1e9:.3g} GB"


def scene_counts(scene) -> tuple[int, int]:
    """Particles and springs the scene's bodies will have (bodies that cannot say: none)."""
    particles = springs = 0
    for body in scene.bodies:
        counts = getattr(body, "counts", None)
        if counts is not None:
            body_particles, body_springs = counts()
            particles, springs = particles + body_particles, springs + body_springs
    return particles, springs


def check_scene_size(scene) -> None:
    """Refuse a scene whose model the machine cannot hold, naming the body that makes it so."""
    particles, springs = scene_counts(scene)
    key, value = _largest_body(scene)
    needed = BYTES_PER_PARTICLE * particles + BYTES_PER_SPRING * springs
    memory = machine_memory()
    require(memory is None or needed <= MODEL_MEMORY_SHARE * memory, key, value,
            f"makes {particles:,} particles and {springs:,} springs, about {gigabytes(needed)} "
            f"to build and simulate; this machine has {gigabytes(memory or 0)} of memory")
    require(particles <= MAX_PARTICLES, key, value,
            f"makes {particles:,} particles; at most {MAX_PARTICLES:,} are possible")


def check_reading(key: str, value, size: int, bytes_per_byte: float, what: str) -> None:
    """Refuse a file of ``size`` bytes whose reading (``bytes_per_byte`` of memory per byte of
    it, as traced for its reader) would take more than the model's share of the machine's
    memory: measured before a byte is read, as a scene's size is before it is built."""
    needed = bytes_per_byte * size
    memory = machine_memory()
    require(memory is None or needed <= MODEL_MEMORY_SHARE * memory, key, value,
            f"is {size:,} bytes; reading {what} that large takes about {gigabytes(needed)}, and "
            f"this machine has {gigabytes(memory or 0)} of memory")


def _largest_body(scene) -> tuple[str, object]:
    """The key and value to blame: the size parameter of the body with the most particles."""
    sizes = [(getattr(body, "counts", lambda: (0, 0))()[0], b, body)
             for b, body in enumerate(scene.bodies)]
    if not sizes:
        return "bodies", []
    _, b, body = max(sizes, key=lambda item: item[0])
    if hasattr(body, "particles_per_edge"):
        return f"bodies.{b}.particles_per_edge", body.particles_per_edge
    return f"bodies.{b}", type(body).__name__
