"""Gradients through a body's contact with itself (gradients/body_contact.py, and under
implicit_euler gradients/implicit_bodies.py), against central finite differences of the
forward run: a mesh cloth folded in two, its upper layer thrown down onto its lower one, which
lies on a plane or is pinned (the same stencils as two bodies' contacts, of one self-colliding
body: points against its own triangles and its own edges against each other, but never a pair
that shares a surface edge). Under implicit_euler the upper layer lands on the lower one,
pinned or on the plane (the solve's own pairs, and the Newton iteration solved again when a
solve brings more into contact); a self-colliding cloth that never touches itself has its
gradient."""
import numpy as np
import pytest

from springsim.bodies.cloth import Cloth
from springsim.springs import SpringParameters
from springsim.gradients import body_contact, gradient, implicit_bodies
from springsim.scene import Scene
from springsim.terrains.plane import Plane
from springsim.gradients.parameters import parameter
from test_gradients import (STEPS, TIGHT, assert_gradients_match, central_difference,
                            weighted_squares)

EXPLICIT = [name for name in STEPS if name != "implicit_euler"]

KEYS = ["bodies.0.velocity", "bodies.0.structural.ks", "gravity", "bodies.0.friction",
        "bodies.0.restitution", "bodies.0.particle_mass", "drag"]
SIDE, GAP = 4, 0.03   # vertices along each edge of a layer; the layers 3 cm apart


def folded_sheet(path):
    """An OBJ of a 0.3 m square sheet folded in two along x = 0.3: a layer at y = 0 (vertices
    0 to 15), one at y = GAP above it (16 to 31) and the fold's strip of quads between them."""
    spacing = 0.3 / (SIDE - 1)
    vertices = [(i * spacing, layer * GAP, j * spacing)
                for layer in (0, 1) for i in range(SIDE) for j in range(SIDE)]

    def at(layer, i, j):
        return 1 + layer * SIDE * SIDE + i * SIDE + j   # OBJ numbers from 1

    faces = [(at(layer, i, j), at(layer, i + 1, j), at(layer, i + 1, j + 1), at(layer, i, j + 1))
             for layer in (0, 1) for i in range(SIDE - 1) for j in range(SIDE - 1)]
    faces += [(at(0, SIDE - 1, j), at(0, SIDE - 1, j + 1), at(1, SIDE - 1, j + 1),
               at(1, SIDE - 1, j)) for j in range(SIDE - 1)]
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in vertices)
                    + "".join("f " + " ".join(map(str, face)) + "\n" for face in faces))
    return str(path)


@pytest.fixture(scope="module")
def sheet(tmp_path_factory):
    return folded_sheet(tmp_path_factory.mktemp("folded") / "folded.obj")


def folded(file, lower="floor", speed=2.5):
    """The folded sheet thrown down at ``speed`` (m/s) and sideways: its lower layer stopped by
    a plane 4 mm below it (inside its contact band) or pinned, its upper layer landing on it."""
    pinned = list(range(SIDE * SIDE)) if lower == "pins" else "none"
    springs = SpringParameters(ks=2000.0, kd=5.0)
    cloth = Cloth(file=file, velocity=(0.3, -speed, 0.1), pinned=pinned, structural=springs,
                  particle_mass=1.0,
                  shear=springs, bend=springs, thickness=0.012, friction=0.3,
                  static_friction=0.45, restitution=0.3)
    terrains = [Plane(point=(0.0, -0.004, 0.0), friction=0.5, restitution=0.4)] \
        if lower == "floor" else []
    return Scene(bodies=[cloth], terrains=terrains, drag=0.1)


@pytest.mark.parametrize("lower", ["floor", "pins"])
@pytest.mark.parametrize("integrator", EXPLICIT)
def test_self_contact_gradients_match_finite_differences(sheet, integrator, lower):
    assert_gradients_match(lambda: folded(sheet, lower), integrator, KEYS)


@pytest.mark.parametrize("lower, speed", [("pins", 0.8), ("floor", 0.5)])
def test_implicit_euler_self_contact_matches_finite_differences(sheet, monkeypatch, lower,
                                                                 speed):
    """The upper layer thrown onto the lower one at 1/100 s, the lower one pinned or on the
    plane: the solve's own pairs, those in contact at a step's start and those a solve brings
    into contact, after which the iteration is solved again with them
    (implicit_bodies.PenaltyStep.regrow; on the plane the terrain replay's, where the
    iteration solved again hands its friction dampers on). On the plane at 0.8 m/s the
    forward's active sets change within 1e-7 of the values: no central difference is stable
    there (steps of 1e-7 and 1e-8 differ by 2e-3 for drag)."""
    grew = []
    original = implicit_bodies.PenaltyStep.regrow

    def spy(self, dv, ddv):
        grew.append(original(self, dv, ddv))
        return grew[-1]

    monkeypatch.setattr(implicit_bodies.PenaltyStep, "regrow", spy)

    def scene():
        return folded(sheet, lower, speed)
    _, grads = gradient(scene(), weighted_squares, KEYS, duration=10 * 0.01,
                        integrator="implicit_euler", dt=0.01, fps=25, **TIGHT["implicit_euler"])
    assert any(grew)
    # the active sets and the own pairs that join them change within 1e-4 of these values (a
    # difference at 1e-4 of the velocity is 20 times the derivative): steps of 1e-7 stay on
    # one side
    for name in KEYS:
        base = parameter(scene(), name).value
        for j in range(base.size):
            step = 1e-7 * max(abs(base.ravel()[j]), 1.0)
            expected = central_difference(scene(), "implicit_euler", name, base, j, step)
            assert np.ravel(grads[name])[j] == pytest.approx(expected, rel=1e-5, abs=1e-6), \
                (name, j)


def test_the_fold_touches_itself_with_points_and_edges(sheet, monkeypatch):
    """The case above has self contacts of both kinds in the adjoint's replay, and none of a
    pair that shares a surface edge."""
    found = []
    original = body_contact.touching

    def spy(physical, x, start):
        contacts = original(physical, x, start)
        found.append(contacts)
        return contacts

    monkeypatch.setattr(body_contact, "touching", spy)
    gradient(folded(sheet), weighted_squares, ["gravity"], duration=10 * STEPS["rk4"],
             integrator="rk4", dt=STEPS["rk4"], fps=1 / (4 * STEPS["rk4"]))
    kinds = np.concatenate([c.geometry.kind for c in found])
    assert {body_contact.POINT, body_contact.EDGE} <= set(kinds.tolist())
    nodes = np.concatenate([c.nodes for c in found])
    upper = nodes >= SIDE * SIDE
    # every contact joins the two layers: a particle of one against a triangle or an edge
    # with a corner of the other (the fold's strip has corners in both)
    assert np.all(upper.any(axis=1) & ~upper.all(axis=1))


def test_implicit_euler_follows_a_self_colliding_cloth_that_never_touches_itself():
    """A small hanging cloth with self_collision on (the cloth's default)."""
    def hanging():
        return Scene(bodies=[Cloth(particles_per_edge=4, width=1.0, height=1.0,
                                   pinned="edge", particle_mass=0.1,
                                   velocity=(0.2, 0.0, -0.1))], terrains=[], drag=0.1)
    assert hanging().bodies[0].self_collision
    assert_gradients_match(hanging, "implicit_euler", ["bodies.0.structural.ks", "gravity"])
