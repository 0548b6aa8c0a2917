"""Shared builders for the physics tests: small cubes in small scenes, and the suite's tiers.

The physics tests want small, fast, fully specified systems: a few particles, chosen springs,
gravity on or off, zero or one terrain. The ``cube_simulation`` fixture builds one; with
``perturb_seed`` it also deforms and spins it so that every spring is stretched and every damper
works.

Tiers: ``default`` (every cheap oracle, the tier ./test.sh runs), ``slow`` (tests marked
``slow``: long scenarios, presets, the documentation's examples, thread bit-identity) and
``external`` (tests marked ``external``: Blender, Chromium, Xvfb, Dask). ``--tier`` picks them,
a comma-separated list or ``all``; CI (.ci/run) runs all three.
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


TIERS = ("default", "slow", "external")


def pytest_addoption(parser):
    parser.addoption("--tier", default="default",
                     help="the tiers to run: default, slow, external, a comma-separated list of "
                          "them, or all (default: default)")


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: the slow tier (long scenarios; ./test.sh --tier slow)")
    config.addinivalue_line("markers",
                            "external: the external tier (Blender, Chromium, Xvfb, Dask; "
                            "./test.sh --tier external)")
    config.springsim_tiers = chosen_tiers(config.getoption("--tier"))


def chosen_tiers(option: str) -> set:
    """The tiers ``--tier`` names, refused in one line unless each is a tier or ``all``."""
    names = {name.strip() for name in option.split(",")}
    if names == {"all"}:
        return set(TIERS)
    unknown = names - set(TIERS)
    if unknown:
        raise pytest.UsageError(f"--tier = {option!r}: must be all or a comma-separated list of "
                                f"{', '.join(TIERS)}")
    return names


def tier_of(item) -> str:
    """An external mark wins over a slow one: a slow Blender test needs Blender first."""
    for tier in ("external", "slow"):
        if item.get_closest_marker(tier) is not None:
            return tier
    return "default"


def pytest_collection_modifyitems(config, items):
    chosen = config.springsim_tiers
    kept = [item for item in items if tier_of(item) in chosen]
    left = [item for item in items if tier_of(item) not in chosen]
    if left:
        config.hook.pytest_deselected(items=left)
        items[:] = kept


def pytest_report_header(config):
    left = [tier for tier in TIERS if tier not in config.springsim_tiers]
    ran = ", ".join(tier for tier in TIERS if tier in config.springsim_tiers)
    if not left:
        return f"tiers: {ran}"
    return (f"tiers: {ran} (the {' and '.join(left)} tier{'s' if len(left) > 1 else ''} "
            f"deselected: ./test.sh --tier all runs every tier)")
