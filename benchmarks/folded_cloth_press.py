"""A 0.3 m jelly cube dropped onto a cloth folded in half on the floor, under implicit_euler: the
most edge-triangle crossings of the cloth with itself at any step of 1 s (issue 10, part 4).

    .venv/bin/python benchmarks/folded_cloth_press.py [SHIFT]

The 1 m, 16 x 16 cloth lies on the floor with its half z > 0 laid back over the other half, 1.5
thicknesses above it and SHIFT metres aside along x (default 0.023, a third of the spacing;
0 puts every particle of the top layer exactly over one of the bottom layer). The cube (4 x 4 x 4
particles of 0.5 or 2 kg) falls from 0.45 m above it at 0, 2 or 5 m/s, at dt 1/60 and 1/30 s.
Crossings are counted with tests/crossings.py (plain NumPy, independent of springsim) after
every step; "cube lowest" is its lowest particle over the run (it often slides off the folded
stack onto the floor, so 0 says nothing of the cloth).

Measured 2026-11-25 (shift 0.023), worst crossings before the solve took a body's own pairs
(commit ce35643) and after (the own pairs in contact at the step's start): 1/60 s: 0 -> 0 at
0 m/s, 0/8 -> 0/0 at 2 m/s (0.5/2 kg), 0/64 -> 0/64 at 5 m/s; 1/30 s: 0 -> 0 at 0 and 2 m/s,
0/1,700 -> 0/1,265 at 5 m/s. With shift 0: 2 m/s 10/12 -> 0/0 at 1/60 s and 0/32 -> 0/0 at
1/30 s; 5 m/s 28/2,191 -> 20/99 at 1/60 s and 0/2,336 -> 0/38 at 1/30 s. (Taking every listed
own pair, farther ones too, did better at 5 m/s, 4 and 12 with the shift, but made the result
depend on when the list was found: a resumed run did not step as the one that went on.)
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


def main():
    shift = float(sys.argv[1]) if len(sys.argv) > 1 else 0.023
    for dt in (1.0 / 60.0, 1.0 / 30.0):
        for speed in (0.0, 2.0, 5.0):
            for particle_mass in (0.5, 2.0):
                worst, lowest = worst_crossings(dt, speed, particle_mass, shift)
                print(f"dt {dt:.4f} s, {speed:.0f} m/s, cube particles {particle_mass} kg: "
                      f"worst {worst} crossings, cube lowest {lowest:.3f} m", flush=True)


if __name__ == "__main__":
    main()
