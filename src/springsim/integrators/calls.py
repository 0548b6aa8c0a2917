"""A compiled call: a kernel and its arguments (what warmup compiles and is_compiled asks
about). Its own module, so that the step's pieces (_steps.py) can name their calls without
importing the integrators' base, which chooses among them (plain.py)."""
from typing import NamedTuple


class KernelCall(NamedTuple):
    """A compiled kernel and the arguments a step calls it with. What Numba compiles (and
    caches) is the kernel for these arguments' types: a new kernel or new types compile anew
    (warmup.is_compiled asks the cache)."""

    kernel: object       # a Numba dispatcher
    arguments: tuple
