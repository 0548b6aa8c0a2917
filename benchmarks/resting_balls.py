"""Do the reference cloth's four balls come to rest under implicit_euler? (issue 30, part 7)

    .venv/bin/python benchmarks/resting_balls.py [--duration 8] [--drag 5]

The built-in `cloth-balls` with scene drag 5 N s/m, run under implicit_euler at several steps
and Newton iterations; printed for each: the fastest particle's speed over the last second, the
fastest at the end and how many particles move faster than 1 cm/s there. A scene whose only
source of energy is gravity, with drag, must come to rest.
"""
import argparse
import json

import numpy as np

import springsim
from springsim.presets import preset

CASES = [(1 / 100, 1), (1 / 60, 1), (1 / 60, 2), (1 / 30, 1), (1 / 30, 2), (1 / 30, 3)]


def end_speeds(dt: float, newton_iterations: int, duration: float, drag: float) -> dict:
    scene = preset("cloth-balls")
    scene.drag = drag
    scene.implicit.newton_iterations = newton_iterations
    simulation = springsim.Simulation(scene, integrator="implicit_euler", dt=dt)
    simulation.advance(duration - 1.0)
    last_second = 0.0
    for _ in range(int(round(1.0 / dt))):
        simulation.step(1)
        last_second = max(last_second, float(np.linalg.norm(simulation.velocities, axis=1).max()))
    speed = np.linalg.norm(simulation.velocities, axis=1)
    return {"dt": dt, "newton_iterations": newton_iterations,
            "fastest_last_second_m_s": last_second, "fastest_m_s": float(speed.max()),
            "moving_over_1cm_s": int((speed > 0.01).sum())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=8.0)
    parser.add_argument("--drag", type=float, default=5.0)
    args = parser.parse_args()
    for dt, newton in CASES:
        row = end_speeds(dt, newton, args.duration, args.drag)
        print(json.dumps(row))
        print(f"dt 1/{round(1 / dt)} s, {newton} Newton iteration(s): fastest "
              f"{100 * row['fastest_last_second_m_s']:.2f} cm/s over the last second, "
              f"{100 * row['fastest_m_s']:.2f} cm/s at the end, {row['moving_over_1cm_s']} "
              f"particles over 1 cm/s after {args.duration:g} s")


if __name__ == "__main__":
    main()
