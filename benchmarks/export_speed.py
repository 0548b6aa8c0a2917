"""Time exporting a 10,000-particle, 600-frame recording (the issue's figure: USD <= 5 s, MDD
<= 1 s), as quoted in the README:

    .venv/bin/python benchmarks/export_speed.py [--frames 600] [--repeats 3]

The take is the 100 x 100 cloth (10,000 particles, all on its surface, 19,602 triangles) with four
balls, its frames a travelling wave (no simulation: only the export is timed). Each figure is the
best of ``--repeats`` timings of ``springsim.export.export`` from the loaded take to a file on
disk (computing the vertices, encoding, writing, the atomic rename), for every format.
"""
import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from springsim import load_scene
from springsim.export import export, take_from_arrays
from springsim.model import build_model
from springsim.recording_layout import layout_arrays

FORMATS = (".usd", ".usdc", ".usda", ".mdd", ".pc2", ".obj")
LIMITS = {".usd": 5.0, ".mdd": 1.0}     # s, the issue's


def wave_take(frames: int, fps: float = 60.0):
    scene = load_scene("cloth-balls", ["bodies.0.particles_per_edge=100"])
    model = build_model(scene)
    rest = model.initial_positions
    time_ = np.arange(frames) / fps
    phase = rest[:, 0] + rest[:, 2]
    positions = np.repeat(rest[None], frames, axis=0)
    positions[:, :, 1] += 0.2 * np.sin(phase[None] - 3.0 * time_[:, None])
    arrays = {"time": time_, "fps": np.asarray(fps), "positions": positions,
              "scene": np.asarray("cloth-wave"), **layout_arrays(model)}
    return take_from_arrays(arrays)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=600)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    take = wave_take(args.frames)
    print(f"{take.positions.shape[1]} particles, {take.frame_count} frames")
    with tempfile.TemporaryDirectory() as folder:
        for extension in FORMATS:
            path = Path(folder) / f"take{extension}"
            best = np.inf
            for _ in range(args.repeats):
                started = time.perf_counter()
                export(take, path)
                best = min(best, time.perf_counter() - started)
            limit = LIMITS.get(extension)
            verdict = f"  (limit {limit:g} s: {'ok' if best <= limit else 'OVER'})" if limit else ""
            size = path.stat().st_size / 1e6
            print(f"{extension:<6} {best:6.2f} s  {size:7.1f} MB{verdict}")


if __name__ == "__main__":
    main()
