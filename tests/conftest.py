"""Shared builders for the physics tests: small cubes in small scenes.

The physics tests want small, fast, fully specified systems: a few particles, chosen springs,
gravity on or off, zero or one terrain. The ``cube_simulation`` fixture builds one; with
``perturb_seed`` it also deforms and spins it so that every spring is stretched and every damper
works.
"""
import numpy as np
import pytest

from springsim import Simulation
from springsim.bodies.cube import Cube
from springsim.scene import Scene
from springsim.springs import SpringParameters

NO_GRAVITY = (0.0, 0.0, 0.0)
EARTH_GRAVITY = (0.0, -9.8, 0.0)


def build_cube_simulation(integrator="rk4", dt=1e-3, *, gravity=NO_GRAVITY, drag=0.0,
                          terrains=(), ks=50.0, kd=0.0, perturb_seed=None,
                          **cube_options) -> Simulation:
    """One cube (3 x 3 x 3, edge 1 m, 1 kg particles, centred at the origin unless told) with the
    same ``ks``/``kd`` for structural, shear and bend springs unless given per kind."""
    springs = SpringParameters(ks, kd)
    options = {"particles_per_edge": 3, "edge_length": 1.0, "position": (0.0, 0.0, 0.0),
               "structural": springs, "shear": springs, "bend": springs, **cube_options}
    scene = Scene(name="test", bodies=[Cube(**options)], terrains=list(terrains),
                  integrator=integrator, dt=dt, gravity=gravity, drag=drag)
    simulation = Simulation(scene)
    if perturb_seed is not None:
        perturb(simulation, perturb_seed)
    return simulation


def perturb(simulation: Simulation, seed: int = 1, squeeze: float = 0.9,
            spin=(0.0, 1.0, 0.5), jitter: float = 0.02) -> Simulation:
    """Squeeze the cube about its centre, spin it, and add random displacements and velocities.

    Pinned particles are left where they are, at rest.
    """
    rng = np.random.default_rng(seed)
    x, v = simulation.state.positions, simulation.state.velocities
    free = ~simulation.model.pinned
    centre = x.mean(axis=0)
    deformed = centre + squeeze * (x - centre) + jitter * rng.standard_normal(x.shape)
    moving = np.cross(spin, x - centre) + 5 * jitter * rng.standard_normal(x.shape)
    x[free], v[free] = deformed[free], moving[free]
    return simulation


@pytest.fixture(scope="session")
def cube_simulation():
    return build_cube_simulation
