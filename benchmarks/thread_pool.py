"""Why the threaded kernels are Numba parallel kernels and not nogil kernels on a Python thread
pool (issue 14, part 2): the cost of one parallel section both ways, for a trivial loop over
1,000 and 1,000,000 numbers cut in two fixed halves.

    .venv/bin/python benchmarks/thread_pool.py

A thread pool returns to Python for every section (an RK4 step has about 30), where a parallel
kernel runs the whole loop of steps in one compiled call.
"""
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from numba import njit, prange

REPEATS = 2000


@njit(nogil=True)
def add_one(a, low, high):
    for i in range(low, high):
        a[i] += 1.0


@njit(parallel=True)
def add_one_in_halves(a):
    n = a.shape[0]
    for k in prange(2):
        for i in range(k * n // 2, (k + 1) * n // 2):
            a[i] += 1.0


def main():
    pool = ThreadPoolExecutor(2)
    for n in (1000, 1_000_000):
        a = np.zeros(n)

        def via_pool():
            for future in [pool.submit(add_one, a, k * n // 2, (k + 1) * n // 2)
                           for k in range(2)]:
                future.result()

        for name, section in (("nogil kernels on a thread pool", via_pool),
                              ("a parallel kernel", lambda: add_one_in_halves(a))):
            section()   # compile
            began = time.perf_counter()
            for _ in range(REPEATS):
                section()
            per_section = (time.perf_counter() - began) / REPEATS
            print(f"{n:>9,} numbers, {name:31s} {1e6 * per_section:8.1f} us per section")


if __name__ == "__main__":
    main()
