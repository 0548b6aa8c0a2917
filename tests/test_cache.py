"""The compiled-kernel cache: its folder is named after the kernel sources only; other versions'
folders are deleted once unused for STALE_DAYS, the current one and recently used ones are kept."""
import os
import shutil
import time
from pathlib import Path

from springsim._jit import PACKAGE, STALE_DAYS, kernel_sources, remove_stale_caches, \
    source_fingerprint


def test_only_other_versions_unused_for_stale_days_are_deleted(tmp_path):
    now = time.time()
    day = 86400
    ages = {"numba-current": 400, "numba-old": STALE_DAYS + 1, "numba-recent": STALE_DAYS - 1,
            "not-a-cache": 400}
    for name, age in ages.items():
        folder = tmp_path / name
        (folder / "sub").mkdir(parents=True)
        (folder / "sub" / "kernel.nbc").write_bytes(b"x")
        os.utime(folder, (now - age * day, now - age * day))
    deleted = remove_stale_caches(tmp_path, keep=tmp_path / "numba-current", now=now)
    assert deleted == [tmp_path / "numba-old"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["not-a-cache", "numba-current",
                                                          "numba-recent"]


def _edited(package, relative: str) -> str:
    """The fingerprint after appending a comment to one file of a copy of the package."""
    with open(package / relative, "a") as file:
        file.write("\n# edited\n")
    return source_fingerprint(package)


def test_only_kernel_sources_name_the_cache(tmp_path):
    package = tmp_path / "springsim"
    shutil.copytree(PACKAGE, package, ignore=shutil.ignore_patterns("__pycache__"))
    original = source_fingerprint(package)
    assert original == source_fingerprint(PACKAGE)   # names relative to the package
    # modules no kernel depends on: the compiled kernels stay valid
    for relative in ("cli.py", "commands/run.py", "recording.py", "simulation.py",
                     "viewer/controls.py", "scene.py"):
        assert _edited(package, relative) == original, relative
    # a kernel's own file, a file whose kernels another file calls (forces.py: every
    # integrator), and a module whose constants kernels compile in (terrains.PLANE, via
    # collision/response/terrain.py): each gives a fresh cache
    terrains = "terrains.py" if (package / "terrains.py").is_file() else "terrains/__init__.py"
    for relative in ("integrators/rk4.py", "forces.py", terrains):
        changed = _edited(package, relative)
        assert changed != original, relative
        original = changed
    # a new module with kernels counts from the start
    (package / "new_kernels.py").write_text("from ._jit import kernel\n")
    assert source_fingerprint(package) != original


def test_kernel_sources_are_the_kernel_modules_and_their_imports():
    names = {path.relative_to(PACKAGE).as_posix() for path in kernel_sources()}
    assert {"_jit.py", "forces.py", "collision/response/terrain.py", "integrators/rk4.py",
            "integrators/implicit_euler.py", "implicit/constraints.py"} <= names
    assert not names & {"cli.py", "simulation.py", "recording.py", "commands/run.py"}


TESTS = Path(__file__).resolve().parent
FOLDED_CLOTH_RUN = f"""
import hashlib
import sys
sys.path.insert(0, {str(TESTS)!r})
from test_implicit_surface_contact import cube_onto_folded_cloth

def folded_cloth_run():
    simulation = cube_onto_folded_cloth(1.0 / 60.0, 5.0, shift=0.031)
    simulation.step(8)
    return hashlib.sha256(simulation.positions.tobytes()
                          + simulation.velocities.tobytes()).hexdigest()
"""


def test_a_run_compiled_here_and_one_loaded_from_the_cache_are_bit_identical():
    """The same input gives the same bits whether the kernels were compiled in this process or
    loaded from the cache (as in a second process, or a sweep's workers). With LLVM's fast-math
    flags (reassoc, contract) they did not: a backward-Euler step compiled in the process
    differed from the cached one by 3e-17 m, and a cube pressing a folded cloth ended 0.5 m
    apart after 8 steps (benchmarks/folded_cloth_press.py: 8 or 1,628 crossings for one input).
    On a clean machine (CI) the kernels here are compiled in this process and the second process
    loads them; on a warm cache both load them and the test proves less."""
    import subprocess
    import sys

    namespace = {}
    exec(FOLDED_CLOTH_RUN, namespace)
    here = namespace["folded_cloth_run"]()
    there = subprocess.run([sys.executable, "-c", FOLDED_CLOTH_RUN + "print(folded_cloth_run())"],
                           check=True, capture_output=True, text=True, timeout=600).stdout
    assert there.split()[-1] == here


SORTS = """
import numpy as np
from numba import njit

@njit(cache=True)
def by_argsort(a):
    return a[np.argsort(a)]

@njit(cache=True)
def by_sort(a):
    return np.sort(a)

@njit(cache=True)
def both(a):
    return by_sort(a), by_argsort(a)
"""
# A process compiles one of the kernels above into the shared cache, its function counter
# first moved on by ``skip``, and prints whether its answers are sorted.
SORTS_RUN = """
import sys
import numpy as np
if sys.argv[1] == "springsim":
    import springsim._jit
from numba.core.bytecode import FunctionIdentity
for _ in range(int(sys.argv[3])):
    next(FunctionIdentity._unique_ids)
import sorts
a = np.random.default_rng(0).integers(0, 1000, 200)
answers = getattr(sorts, sys.argv[2])(a)
answers = answers if isinstance(answers, tuple) else (answers,)
print(all(np.array_equal(answer, np.sort(a)) for answer in answers))
"""


def sorted_in_three_processes(tmp_path, importing):
    """Whether a kernel calling np.sort and np.argsort sorts right when each of those was
    compiled and cached by a process of its own, the argsort one three function ids ahead:
    then, with Numba's own numbering, both processes give quicksort's run_quicksort1 the same
    symbol, one body sorting, the other arg-sorting (numba 0.68)."""
    import subprocess
    import sys

    tmp_path.mkdir()
    (tmp_path / "sorts.py").write_text(SORTS)
    (tmp_path / "run.py").write_text(SORTS_RUN)
    path = os.pathsep.join(filter(None, [str(tmp_path), os.environ.get("PYTHONPATH")]))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), PYTHONPATH=path)
    answers = [subprocess.run([sys.executable, str(tmp_path / "run.py"), importing, kernel, skip],
                              env=env, capture_output=True, text=True, timeout=300).stdout.split()
               for kernel, skip in (("by_argsort", "3"), ("by_sort", "0"), ("both", "0"))]
    return [answer[-1] if answer else "crashed" for answer in answers]


def test_kernels_cached_by_different_processes_link_without_symbol_collisions(tmp_path):
    """springsim numbers each process's compiled functions from a random start (_jit's module
    doc); with Numba's own numbering the same three processes end with a kernel that sorts
    wrong (the control: if it stops failing, Numba has fixed numba#10486)."""
    assert sorted_in_three_processes(tmp_path / "numba", "numba") == ["True", "True", "False"]
    assert sorted_in_three_processes(tmp_path / "springsim", "springsim") == ["True"] * 3


def test_two_processes_saving_one_kernels_signatures_at_once_keep_both(tmp_path, monkeypatch):
    """Numba's cache save reads a kernel's index, takes the first free data file number, and
    writes: two processes compiling one kernel for two signatures at once (warmup's parallel
    compiles) both took number 1, and one signature's index entry named the other's code. Here
    two savers (threads with their own lock descriptors, as processes have) read the index at
    the same moment; each signature must come back with its own data."""
    import threading
    import time

    from numba.core.caching import IndexDataCacheFile

    import springsim._jit  # noqa: F401 - locks the cache's saves

    unlocked_read = IndexDataCacheFile._load_index

    def slow_read(cache_file):   # both savers read before either writes
        overloads = unlocked_read(cache_file)
        time.sleep(0.3)
        return overloads

    monkeypatch.setattr(IndexDataCacheFile, "_load_index", slow_read)
    savers = [IndexDataCacheFile(str(tmp_path), "kernel-1", "stamp") for _ in range(2)]
    threads = [threading.Thread(target=saver.save, args=(f"signature {n}", f"code {n}"))
               for n, saver in enumerate(savers)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    reader = IndexDataCacheFile(str(tmp_path), "kernel-1", "stamp")
    assert [reader.load(f"signature {n}") for n in range(2)] == ["code 0", "code 1"]
