"""Gradients through contact with curved terrains (still spheres, bowls and meshes,
gradients/contact.py and terrain_shapes.py) under the explicit methods, against central finite
differences of the forward run: a cube landing on a sphere's shoulder and sliding off it, one
resting in a bowl, and one landing on a mesh dome (a distance grid, whose normal turns inside
each cell and jumps a little between cells), where the surface's curvature turns the normal
under each particle."""
import functools
import tempfile
from pathlib import Path

import numpy as np
import pytest
import trimesh

from springsim.bodies.cube import Cube
from springsim.scene import Scene
from springsim.terrains import Bowl, MeshTerrain, Sphere
from test_gradients import STEPS, assert_gradients_match

KEYS = ["bodies.0.structural.ks", "terrains.0.friction", "terrains.0.restitution",
        "bodies.0.velocity", "gravity"]
EXPLICIT = ["symplectic_euler", "rk4"]
INTEGRATORS = EXPLICIT + ["implicit_euler"]


def on_sphere():
    """A 3 x 3 x 3 cube dropped at 1.5 m/s onto a sphere of radius 2, a little off its top, so
    that it bounces (restitution 0.5) and slides (friction 0.05) down the shoulder."""
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.3, 2.51, 0.1),
                velocity=(0.3, -1.5, 0.0))
    return Scene(bodies=[cube], drag=0.1,
                 terrains=[Sphere(center=(0.0, 0.0, 0.0), radius=2.0, friction=0.05,
                                  restitution=0.5)])


def in_bowl():
    """A cube settling off-centre into a bowl of radius 4: its outer bottom edge lands on the
    rising wall, at a different slope under each particle, and is held by static friction
    (0.6)."""
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.6, -3.3, 0.0),
                velocity=(0.0, -1.0, 0.0))
    return Scene(bodies=[cube], drag=0.1,
                 terrains=[Bowl(center=(0.0, 0.0, 0.0), radius=4.0, friction=0.6,
                                restitution=0.5)])


@functools.lru_cache(maxsize=None)
def dome_file() -> str:
    """An icosphere of radius 2 (1,280 triangles) written once per session."""
    path = Path(tempfile.mkdtemp()) / "dome.obj"
    trimesh.creation.icosphere(3, radius=2.0).export(path)
    return str(path)


def on_mesh_dome():
    """on_sphere's drop onto the same sphere as a mesh terrain: the normal is the distance
    grid's gradient direction, and it lifts the particles that end a step inside."""
    scene = on_sphere()
    scene.terrains = [MeshTerrain(file=dome_file(), resolution=32, friction=0.05,
                                  restitution=0.5)]
    return scene


def into_mesh_dome():
    """The same drop at 12 m/s: 2.4 cm a step, past the 1 cm contact band, so the impact pass
    lifts particles out of the dome, along a normal whose distance grid's gradient is not
    quite of length 1 (without grad phi in the lift's derivative the gradients differ)."""
    scene = on_mesh_dome()
    scene.bodies[0].velocity = (0.3, -12.0, 0.0)
    return scene


SCENES = {"sphere": on_sphere, "bowl": in_bowl, "mesh": on_mesh_dome,
          "mesh-lifted": into_mesh_dome}


def touches(scene, integrator):
    """How many particle-steps the run spends in the terrain's contact band (the test is
    empty without contact)."""
    import springsim

    simulation = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    count = 0
    for _ in range(10):
        simulation.step(1)
        phi = scene.terrains[0].signed_distance(simulation.positions,
                                                simulation.model.arrays.terrain_offset)
        count += int(np.sum(phi < simulation.model.arrays.terrain_epsilon[0]))
    return count


@pytest.mark.parametrize("case", list(SCENES))
@pytest.mark.parametrize("integrator", INTEGRATORS)
def test_curved_contact_matches_finite_differences(integrator, case):
    assert touches(SCENES[case](), integrator) > 0
    assert_gradients_match(SCENES[case], integrator, KEYS)


@pytest.mark.parametrize("case", ["sphere", "mesh-lifted"])
def test_implicit_curved_contact_gradient_is_exact(case, monkeypatch):
    """Under implicit_euler a curved terrain's normal enters every solve, update and friction
    cap of a step, each a small share of the gradient (some 1e-6 of it): checked against
    central differences to 2e-7, which these steps' differences reach (1e-8 typically). The
    landing on the mesh caps carried friction dampers, whose share is checked too."""
    from springsim.gradients import gradient, implicit_contact
    from springsim.gradients.parameters import parameter
    from test_gradients import TIGHT, central_difference, weighted_squares

    caps = []
    cap_adjoint = implicit_contact.cap_adjoint
    monkeypatch.setattr(implicit_contact, "cap_adjoint",
                        lambda *args: caps.append(len(args[4].index)) or cap_adjoint(*args))
    names, dt = ["bodies.0.velocity", "terrains.0.friction", "bodies.0.structural.ks"], 0.01
    _, grads = gradient(SCENES[case](), weighted_squares, names, duration=10 * dt,
                        integrator="implicit_euler", dt=dt, fps=1 / (4 * dt),
                        **TIGHT["implicit_euler"])
    assert sum(caps) > 0
    for name in names:
        base = parameter(SCENES[case](), name).value
        for j in range(base.size):
            step = 1e-5 * max(abs(base.ravel()[j]), 1.0)
            expected = central_difference(SCENES[case](), "implicit_euler", name, base, j, step)
            assert np.ravel(grads[name])[j] == pytest.approx(expected, rel=2e-7, abs=1e-9), \
                (name, j)
