"""The memory a model really takes, against the estimate that refuses scenes up front.

``springsim.sizes`` refuses a scene before building it when BYTES_PER_PARTICLE * particles +
BYTES_PER_SPRING * springs exceeds three quarters of the machine's memory. This script measures
the peak resident memory of building a cube and taking one step, per integrator, each in a
process of its own, and prints it beside the estimate (the estimate should stay above it).

    .venv/bin/python benchmarks/model_memory.py [PARTICLES_PER_EDGE ...]   (default: 20 40)
"""
import json
import subprocess
import sys

MEASURE = """
import json, resource, sys
from springsim import Simulation, load_scene
n, integrator = int(sys.argv[1]), sys.argv[2]
def peak_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
Simulation(load_scene("jelly-plane", ["bodies.0.particles_per_edge=3"]),
           integrator=integrator).step(1)            # kernels compiled or loaded first
before = peak_mb()
sim = Simulation(load_scene("jelly-plane", [f"bodies.0.particles_per_edge={n}",
                                            f"bodies.0.position.1={n}"]), integrator=integrator)
sim.step(1)
print(json.dumps({"particles": sim.model.particle_count, "springs": len(sim.model.springs),
                  "measured_mb": peak_mb() - before}))
"""


def main(edges) -> None:
    from springsim.integrators import integrator_names
    from springsim.sizes import BYTES_PER_PARTICLE, BYTES_PER_SPRING

    print(f"{'N':>4} {'integrator':<20} {'particles':>10} {'springs':>11} {'measured MB':>12} "
          f"{'estimate MB':>12}")
    for n in edges:
        for integrator in integrator_names():
            result = json.loads(subprocess.run(
                [sys.executable, "-c", MEASURE, str(n), integrator], check=True,
                capture_output=True, text=True).stdout)
            estimate = (BYTES_PER_PARTICLE * result["particles"]
                        + BYTES_PER_SPRING * result["springs"]) / 1e6
            print(f"{n:>4} {integrator:<20} {result['particles']:>10,} {result['springs']:>11,} "
                  f"{result['measured_mb']:>12.0f} {estimate:>12.0f}")


if __name__ == "__main__":
    main([int(n) for n in sys.argv[1:]] or [20, 40])
