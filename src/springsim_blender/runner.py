"""The simulation's own process, and the per-object point caches it fills.

Blender starts ``PYTHON worker.py`` (springsim and Numba load there, never in Blender, so a crash
or a divergence cannot take Blender down), then reads the frames the worker streams, turns them
from springsim's Y-up world into each object's own space at that frame and appends them to the
object's PC2, which its Mesh Cache modifier plays. At the end the object's cache is rewritten from
springsim's own take (written whole or not at all); a cancelled or failed run keeps what was
computed.
"""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np

from . import point_cache
from .scene_export import B2S

PYTHON_FILE = "springsim_python.txt"     # written into the zip by `springsim blender-addon`
ENVIRONMENT = "SPRINGSIM_PYTHON"
INSTALL = ("install springsim in a Python 3.11+ (pip install springsim, or the repository's "
           "./run.sh), then run `springsim blender-addon springsim.zip` there and install that "
           "zip, or set that Python in the extension's preferences")


class RunFailed(Exception):
    """The simulation could not start or did not finish: one line for Blender's report."""


def python_candidates(preference: str = "") -> list[tuple[str, str]]:
    """(path, where it came from) in the order tried: the preferences' field, the environment
    variable, the Python that wrote the extension's zip, then the Python Blender runs in (a
    bpy-as-a-module session in springsim's own environment)."""
    found = []
    if preference:
        found.append((bpy_path(preference), "the extension's preferences"))
    if os.environ.get(ENVIRONMENT):
        found.append((os.environ[ENVIRONMENT], f"${ENVIRONMENT}"))
    embedded = Path(__file__).with_name(PYTHON_FILE)
    if embedded.is_file():
        found.append((embedded.read_text().strip(), "the zip's springsim_python.txt"))
    found.append((sys.executable, "the Python Blender runs"))
    return found


def bpy_path(path: str) -> str:
    try:
        import bpy
        return bpy.path.abspath(path)
    except (ImportError, AttributeError):
        return path


def choose_python(preference: str = "") -> tuple[str, str]:
    """The first candidate that exists: given explicitly (preferences, environment), it is used
    even when wrong, so that its error is the one reported."""
    candidates = python_candidates(preference)
    for path, source in candidates:
        if os.path.isfile(path) and os.access(path, os.X_OK):
            return path, source
        if source != "the Python Blender runs" and not source.startswith("the zip"):
            raise RunFailed(f"springsim: no Python at {path!r} (from {source}); {INSTALL}")
    raise RunFailed(f"springsim: no Python to run springsim with; {INSTALL}")


class Run:
    """One simulation of an exported scene, filling its objects' caches as frames come."""

    def __init__(self, exported, caches: dict, python: str, source: str = ""):
        self.exported, self.caches = exported, caches   # caches: object name -> PC2 path
        self.python, self.source = python, source
        folder = exported.folder
        self.stream = folder / "stream.pc2"
        self.take = folder / "take.pc2"
        self.log = folder / "springsim.log"
        self.shown = 0          # frames already in the objects' caches
        self.process = None

    def start(self) -> None:
        for path in (self.stream, self.take, *self.caches.values()):
            Path(path).unlink(missing_ok=True)
        worker = Path(__file__).with_name("worker.py")
        command = [self.python, str(worker), str(self.exported.scene_file), str(self.stream),
                   str(self.take), repr(self.exported.fps)]
        with open(self.log, "wb") as log:
            try:
                self.process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT,
                                                stdin=subprocess.DEVNULL,
                                                cwd=str(self.exported.folder))
            except OSError as error:
                raise RunFailed(f"springsim: cannot start {self.python} ({error}); {INSTALL}")

    @property
    def running(self) -> bool:
        return self.process is not None and self.process.poll() is None

    def progress(self) -> float:
        return self.shown / self.exported.frame_count

    def update(self) -> int:
        """Move the frames streamed since the last call into the objects' caches; how many."""
        frames = point_cache.read(self.stream, first=self.shown)
        if len(frames) == 0:
            return 0
        self._write(frames, first=self.shown, append=True)
        self.shown += len(frames)
        return len(frames)

    def wait(self, poll_seconds: float = 0.05) -> None:
        """Until the process ends (background mode), keeping the caches filled."""
        import time
        while self.running:
            time.sleep(poll_seconds)
        self.process.wait()

    def cancel(self) -> None:
        if self.running:
            self.process.terminate()
            try:
                self.process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.update()

    def finish(self) -> None:
        """After the process ended: the objects' caches from springsim's take; RunFailed with
        springsim's own line when it failed (the frames computed are kept)."""
        code = self.process.wait()
        if code == 0 and self.take.is_file():
            frames = point_cache.read(self.take)
            if frames.shape[1] != self.exported.point_count:
                raise RunFailed(f"springsim: the take has {frames.shape[1]} points, the "
                                f"simulated objects {self.exported.point_count} vertices")
            self._write(frames, first=0, append=False)
            self.shown = len(frames)
            self.stream.unlink(missing_ok=True)      # the take says it all now
            return
        self.update()
        raise RunFailed(self.failure(code))

    def failure(self, code: int) -> str:
        lines = [line.strip() for line in self.log.read_text(errors="replace").splitlines()
                 if line.strip()]
        said = [line for line in lines if line.startswith("springsim")]
        if code == 6 or any("No module named 'springsim'" in line for line in lines):
            return f"springsim is not installed in {self.python} (from {self.source}); {INSTALL}"
        if said:
            return said[-1]
        last = lines[-1] if lines else "no output"
        return f"springsim stopped (exit code {code}): {last} (see {self.log})"

    def _write(self, frames: np.ndarray, first: int, append: bool) -> None:
        world = np.asarray(frames, float) @ B2S        # springsim Y up -> Blender Z up
        ones = np.ones(world.shape[:2] + (1,))
        homogeneous = np.concatenate([world, ones], axis=2)
        for target in self.exported.targets:
            part = homogeneous[:, target.offset:target.offset + target.count]
            to_local = target.to_local[first:first + len(frames)]
            local = np.einsum("fij,fvj->fvi", to_local, part)[..., :3]
            path = self.caches[target.name]
            start = float(self.exported.frame_start)
            if append:
                point_cache.append(path, local, start)
            else:
                point_cache.write(path, local, start)


def remove_folder(path) -> None:
    shutil.rmtree(path, ignore_errors=True)
