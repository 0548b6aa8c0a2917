"""Gradients through a body's contact with itself (gradients/body_contact.py), against central
finite differences of the forward run: a mesh cloth folded in two, its upper layer thrown down
onto its lower one, which lies on a plane or is pinned, under the explicit methods (the same
stencils as two bodies' contacts, of one self-colliding body: points against its own triangles
and its own edges against each other, but never a pair that shares a surface edge). Under
implicit_euler a body that touches itself is refused in one line, and one that never does
(self_collision on, as a cloth's default) has its gradient."""
import numpy as np
import pytest

from springsim.bodies.cloth import Cloth
from springsim.springs import SpringParameters
from springsim.errors import SceneError
from springsim.gradients import body_contact, gradient
from springsim.scene import Scene
from springsim.terrains.plane import Plane
from test_gradients import STEPS, assert_gradients_match, weighted_squares

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


def folded(file, lower="floor"):
    """The folded sheet thrown down and sideways: its lower layer stopped by a plane 4 mm below
    it (inside its contact band) or pinned, its upper layer landing on it."""
    pinned = list(range(SIDE * SIDE)) if lower == "pins" else "none"
    springs = SpringParameters(ks=2000.0, kd=5.0)
    cloth = Cloth(file=file, velocity=(0.3, -2.5, 0.1), pinned=pinned, structural=springs,
                  shear=springs, bend=springs, thickness=0.012, friction=0.3,
                  static_friction=0.45, restitution=0.3)
    terrains = [Plane(point=(0.0, -0.004, 0.0), friction=0.5, restitution=0.4)] \
        if lower == "floor" else []
    return Scene(bodies=[cloth], terrains=terrains, drag=0.1)


@pytest.mark.parametrize("lower", ["floor", "pins"])
@pytest.mark.parametrize("integrator", EXPLICIT)
def test_self_contact_gradients_match_finite_differences(sheet, integrator, lower):
    assert_gradients_match(lambda: folded(sheet, lower), integrator, KEYS)


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


def test_implicit_euler_refuses_a_body_touching_itself(sheet):
    with pytest.raises(SceneError, match="self_collision.*touches itself"):
        gradient(folded(sheet), weighted_squares, ["gravity"], duration=10 * 0.01,
                 integrator="implicit_euler", dt=0.01)


def test_implicit_euler_follows_a_self_colliding_cloth_that_never_touches_itself():
    """A small hanging cloth with self_collision on (the cloth's default)."""
    def hanging():
        return Scene(bodies=[Cloth(particles_per_edge=4, width=1.0, height=1.0,
                                   pinned="edge", particle_mass=0.1,
                                   velocity=(0.2, 0.0, -0.1))], terrains=[], drag=0.1)
    assert hanging().bodies[0].self_collision
    assert_gradients_match(hanging, "implicit_euler", ["bodies.0.structural.ks", "gravity"])
