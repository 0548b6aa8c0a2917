"""A 0.3 m jelly cube dropped onto a cloth folded in half on the floor, under implicit_euler: the
most edge-triangle crossings of the cloth with itself at any step of 1 s (issue 10, part 4).

    .venv/bin/python benchmarks/folded_cloth_press.py [SPEED]

The 1 m, 16 x 16 cloth lies on the floor with its half z > 0 laid back over the other half, 1.5
thicknesses above it and shifted aside along x by each of SHIFTS (0 puts every particle of the
top layer exactly over one of the bottom layer; the scene is chaotic, so one shift says little).
The cube (4 x 4 x 4 particles of 0.5 or 2 kg: 32 or 128 kg) falls from 0.45 m above it at SPEED
(default 5 m/s), at dt 1/60 and 1/30 s. Crossings are counted with tests/crossings.py (plain
NumPy, independent of springsim) after every step. Each row: the worst crossings for each shift.

Measured 2026-11-25 at 5 m/s, worst crossings per shift, with the own pairs at the end of each
solve (collision/pair_lists/own_pairs.py), strict IEEE arithmetic (src/springsim/_jit.py) and the
steps
that carry a surface through another taken again in halves (collision/ccd/crossing_check.py):
    1/60 s, 32 kg:  [0, 0, 0, 0, 0, 0]
    1/60 s, 128 kg: [0, 0, 0, 0, 0, 0]
    1/30 s, 32 kg:  [0, 0, 0, 0, 0, 0]
    1/30 s, 128 kg: [0, 0, 0, 0, 0, 0]
At 10 m/s:
    1/60 s, 32 kg:  [0, 0, 2, 5, 0, 0]
    1/60 s, 128 kg: [0, 5, 0, 0, 11, 6]
    1/30 s, 32 kg:  [0, 6, 0, 0, 0, 0]
    1/30 s, 128 kg: [996, 0, 1480, 14, 4, 0]
(the few: sharp folds along a line, between neighbours that self-contact leaves out; the
thousands: steps where even 1/64 of the step crosses, taken whole).
Without the halving (commit 44ffd89) the 128 kg rows were [0, 1246, 0, 1256, 1479, 0] and
[3, 790, 807, 1165, 1065, 8]; with the start's own pairs alone (commit 3f5f397) 16 of the 24
runs crossed. Figures measured before the kernels gave up fast-math depended on whether the
kernels had been compiled in the process or loaded from the cache (1,628 or 8 crossings for one
run: tests/test_cache.py), so older figures compare only roughly.
"""
import sys
from pathlib import Path

import numpy as np

import springsim
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.scene import Scene
from springsim.terrains.plane import Plane

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
from crossings import count_crossings  # noqa: E402  (the tests' independent counter)

EDGE = 16   # cloth particles along each edge


def folded_cloth_and_cube(dt, speed, particle_mass, shift):
    cloth = Cloth(particles_per_edge=EDGE, width=1.0, height=1.0, rotation_degrees=0.0,
                  pinned="none", position=(0.0, 0.05, 0.0))
    weight = Cube(particles_per_edge=4, edge_length=0.3, particle_mass=particle_mass,
                  position=(0.0, 0.6, -0.2), velocity=(0.0, -speed, 0.0))
    simulation = springsim.Simulation(Scene(bodies=[cloth, weight],
                                            terrains=[Plane(point=(0.0, 0.0, 0.0))], dt=dt),
                                      integrator="implicit_euler")
    sheet = simulation.positions[:EDGE ** 2]
    far = sheet[:, 2] > 0.0
    sheet[far, 2] = -sheet[far, 2]
    sheet[far, 1] += 1.5 * cloth.contact_thickness()
    sheet[far, 0] += shift
    simulation.positions[:EDGE ** 2] = sheet
    return simulation


def worst_crossings(dt, speed, particle_mass, shift):
    simulation = folded_cloth_and_cube(dt, speed, particle_mass, shift)
    triangles = np.asarray(simulation.model.bodies[0].surface, np.int64).reshape(-1, 3)
    worst, lowest = 0, np.inf
    for _ in range(round(1.0 / dt)):
        simulation.step(1)
        worst = max(worst, count_crossings(simulation.positions, triangles))
        lowest = min(lowest, simulation.positions[EDGE ** 2:, 1].min())
    return worst, lowest


SHIFTS = (0.0, 0.007, 0.015, 0.023, 0.031, 0.04)   # metres the top layer lies aside


def main():
    speed = float(sys.argv[1]) if len(sys.argv) > 1 else 5.0
    for dt in (1.0 / 60.0, 1.0 / 30.0):
        for particle_mass in (0.5, 2.0):
            worst = [worst_crossings(dt, speed, particle_mass, shift)[0] for shift in SHIFTS]
            print(f"dt {dt:.4f} s, {speed:.0f} m/s, {64 * particle_mass:.0f} kg cube: worst "
                  f"crossings {worst}", flush=True)


if __name__ == "__main__":
    main()
