"""Gradients through body-body contact (gradients/body_contact.py, and under implicit_euler
gradients/implicit_bodies.py), against central finite differences of the forward run: a cube
dropped onto another and sliding on it (point-triangle contacts above the faces, edge-edge
contacts, Coulomb friction that sticks and slides, the stuck contacts' sliding taken back), a
cube overhanging another's corner (every closest-point region of a point against a triangle),
both for the bodies' contact friction and restitution among other keys; the stacked cubes on a
plane (terrain and body contact in each step); the upper cube landing on a layer that pins carry
along a path; two balls thrown onto a cube and into each other (the balls' contact keys too),
and two onto a cloth; and two cubes far apart, where rk4's adjoint takes its kernels. Under
implicit_euler all but the last run too (the solve's penalty springs beside the terrain
constraints, a ball's against particles and against a sheet's triangles at their closest points
or at their centres and corners, their friction, the post-step pass)."""
import numpy as np
import pytest

from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cube import Cube
from springsim.errors import SceneError
from springsim.gradients import gradient
from springsim.gradients import body_contact, stencil_geometry
from springsim.scene import Scene
from test_gradients import STEPS, assert_gradients_match, weighted_squares

CUBE_KEYS = ["bodies.1.velocity", "bodies.0.structural.ks", "gravity", "bodies.1.particle_mass",
             "drag", "bodies.0.friction", "bodies.1.friction", "bodies.0.restitution",
             "bodies.1.restitution"]


def lower_cube():
    """A cube whose contact keys differ from the defaults (restitution 0 is at the end of its
    range, where a central difference cannot be taken)."""
    return Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, 0.5, 0.0), pinned=(),
                friction=0.3, static_friction=0.45, restitution=0.3)


def stacked():
    """A cube 5.5 mm above another (the contact thickness is 5 cm), thrown down and sideways
    onto it, slightly turned, while the lower one rises."""
    lower = lower_cube()
    lower.velocity = (0.0, 0.2, 0.0)
    upper = Cube(particles_per_edge=3, edge_length=1.0, position=(0.3, 1.555, 0.2),
                 velocity=(0.4, -1.0, 0.1), rotation_degrees=3.0,
                 rotation_axis=(1.0, 0.0, 0.5), pinned=(), restitution=0.2)
    return Scene(bodies=[lower, upper], terrains=[], drag=0.1)


def on_floor():
    """The stacked cubes, the lower one pressed onto a plane 4 mm below it (inside its contact
    band) and sliding on it: each step has terrain contact and body contact."""
    from springsim.terrains.plane import Plane
    scene = stacked()
    scene.bodies[0].velocity = (0.2, -0.3, 0.0)
    scene.terrains = [Plane(point=(0.0, -0.004, 0.0), friction=0.5, restitution=0.4)]
    return scene


def on_moving_pins():
    """The stacked cubes, the lower one's top layer pinned on a smooth keyed path that lifts and
    shifts it: the upper one lands on particles that the pins place (each step's contacts have
    pinned corners, with no mass, moving on their path)."""
    from springsim.bodies.pins import Pin, Region
    from springsim.motion import Keyframe, Motion
    scene = stacked()
    path = Motion(interpolation="smooth", keyframes=[
        Keyframe(time=0.0), Keyframe(time=0.05, position=(0.02, 0.03, 0.01))])
    scene.bodies[0].pins = [Pin(region=Region(min=(-1.0, 0.99, -1.0), max=(1.0, 1.01, 1.0)),
                                motion=path)]
    return scene


def overhang():
    """The upper cube over the lower one's corner, 2 cm beyond its edges: its particles meet
    the lower top's corners and edges, and the lower's its faces' edges."""
    upper = Cube(particles_per_edge=3, edge_length=1.0, position=(0.52, 1.548, 0.51),
                 velocity=(0.1, -0.4, 0.05), rotation_degrees=2.0,
                 rotation_axis=(0.3, 0.0, 1.0), pinned=(), restitution=0.2)
    return Scene(bodies=[lower_cube(), upper], terrains=[], drag=0.1)


def balls():
    """A ball 1 mm above the cube's top middle particle thrown down onto it, and a smaller one
    thrown into the first."""
    one = Ball(position=(0.01, 1.201, 0.02), velocity=(0.3, -1.0, 0.0), radius=0.2, mass=2.0)
    two = Ball(position=(0.35, 1.29, 0.06), velocity=(-0.6, -0.5, 0.0), radius=0.15, mass=1.0)
    balls = Balls(balls=[one, two], ball_restitution=0.7, particle_restitution=0.3,
                  particle_friction=0.2)
    return Scene(bodies=[lower_cube(), balls], terrains=[], drag=0.1)


def balls_on_cloth():
    """A ball larger than the cloth's triangles (it meets them at their centres and corners)
    and a smaller one (at their closest points) thrown down onto a cloth pinned at its corners,
    2 mm above it."""
    from springsim.bodies.cloth import Cloth
    from springsim.springs import SpringParameters
    springs = SpringParameters(ks=2000.0, kd=5.0)
    cloth = Cloth(particles_per_edge=5, width=1.0, height=1.0, particle_mass=0.2,
                  structural=springs, shear=springs, bend=springs, self_collision=False)
    big = Ball(position=(0.1, 0.402, 0.05), velocity=(0.3, -1.0, 0.0), radius=0.4, mass=1.0)
    small = Ball(position=(-0.3, 0.102, -0.2), velocity=(-0.2, -1.0, 0.4), radius=0.1, mass=0.5)
    balls = Balls(balls=[big, small], particle_restitution=0.3, particle_friction=0.4)
    return Scene(bodies=[cloth, balls], terrains=[], drag=0.1)


def apart():
    """The stacked cubes 3 m apart: they never touch."""
    scene = stacked()
    scene.bodies[1].position = (3.3, 1.555, 0.2)
    return scene


SCENES = {"stacked": (stacked, CUBE_KEYS), "overhang": (overhang, CUBE_KEYS),
          "on-floor": (on_floor, ["terrains.0.friction", "bodies.0.friction",
                                  "bodies.1.velocity", "gravity"]),
          "on-moving-pins": (on_moving_pins, ["bodies.1.velocity", "bodies.1.friction",
                                              "gravity", "bodies.0.structural.ks"]),
          "balls": (balls, ["bodies.1.balls.0.velocity", "bodies.1.balls.1.mass",
                            "bodies.0.structural.ks", "gravity", "drag",
                            "bodies.1.ball_restitution", "bodies.1.particle_restitution",
                            "bodies.1.particle_friction"]),
          "balls-on-cloth": (balls_on_cloth, ["bodies.1.balls.0.velocity",
                                              "bodies.1.balls.1.mass", "bodies.0.structural.ks",
                                              "bodies.1.particle_friction", "gravity"]),
          "apart": (apart, ["bodies.1.velocity", "bodies.0.structural.ks"])}


CASES = [(integrator, case) for integrator in STEPS for case in SCENES
         if integrator != "implicit_euler" or case != "apart"]


@pytest.mark.parametrize("integrator, case", CASES)
def test_body_contact_gradients_match_finite_differences(integrator, case):
    scene_of, names = SCENES[case]
    assert_gradients_match(scene_of, integrator, names)


@pytest.mark.parametrize("case, kinds", [("stacked", {"face", "edge-edge", "stick", "slide"}),
                                         ("overhang", {"face", "edge", "corner"}),
                                         ("balls", {"ball-point", "ball-ball"})])
def test_the_cases_meet_the_contacts_they_are_for(monkeypatch, case, kinds):
    """The scenes above do reach what they are meant to check: contacts of each kind and each
    branch, taken by the adjoint (else a finite-difference match would prove nothing)."""
    seen = set()
    respond = body_contact.respond

    def spy(physical, x, v, start):
        out = respond(physical, x, v, start)
        if out[2] is not None:
            contacts, passes = out[2].contacts, out[2].passes
            geometry = contacts.geometry
            point = geometry.kind == body_contact.POINT
            seen.update({"face"} if (point & geometry.face).any() else set())
            seen.update({"edge"} if np.isin(geometry.region[point], (2, 4, 5)).any() else set())
            seen.update({"corner"} if np.isin(geometry.region[point], (0, 1, 3)).any()
                        else set())
            seen.update({"edge-edge"} if (geometry.kind == body_contact.EDGE).any() else set())
            ball = geometry.kind == body_contact.BALL
            partner_is_ball = physical.bodies.ball_slot[contacts.nodes[:, 1]] >= 0
            seen.update({"ball-ball"} if (ball & partner_is_ball).any() else set())
            seen.update({"ball-point"} if (ball & ~partner_is_ball).any() else set())
            seen.update({"stick"} if any((p.active & p.stuck).any() for p in passes) else set())
            seen.update({"slide"} if any((p.active & ~p.stuck).any() for p in passes)
                        else set())
        return out

    monkeypatch.setattr("springsim.gradients.adjoints.respond", spy)
    gradient(SCENES[case][0](), weighted_squares, ["gravity"], duration=10 * STEPS["rk4"],
             integrator="rk4", dt=STEPS["rk4"])
    assert kinds <= seen


def test_cubes_apart_take_the_kernels_under_rk4(monkeypatch):
    """Far apart, no step goes through the NumPy contact replay (far_from_bodies)."""
    def fail(*args):
        raise AssertionError("replayed a step of cubes that never touch")

    monkeypatch.setattr("springsim.gradients.adjoints.respond", fail)
    gradient(apart(), weighted_squares, ["gravity"], duration=10 * STEPS["rk4"],
             integrator="rk4", dt=STEPS["rk4"])


def test_implicit_euler_meets_penalty_contacts_of_each_kind(monkeypatch):
    """Under implicit_euler the stacked cubes' steps have active penalty contacts, point-face
    and edge-edge, friction that sticks and slides after the solve, and post-step contacts."""
    from springsim.gradients import implicit_bodies
    seen = set()
    replay = implicit_bodies.replay

    def spy(physical, integrator, solver, h, x, v):
        out = replay(physical, integrator, solver, h, x, v)
        replayed = out[2]
        for one in replayed.iterations:
            active = one.contacts.active
            seen.update({"point"} if (active & (one.contacts.shape == 2)).any() else set())
            seen.update({"edge-edge"} if (active & (one.contacts.shape == 3)).any() else set())
        for one in replayed.friction.passes:
            seen.update({"stick"} if (one.active & one.stuck).any() else set())
            seen.update({"slide"} if (one.active & ~one.stuck).any() else set())
        seen.update({"post-step"} if replayed.response is not None else set())
        return out

    monkeypatch.setattr("springsim.gradients.adjoints.bodies_replay", spy)
    gradient(stacked(), weighted_squares, ["gravity"], duration=10 * STEPS["implicit_euler"],
             integrator="implicit_euler", dt=STEPS["implicit_euler"])
    assert {"point", "edge-edge", "stick", "slide", "post-step"} <= seen


def test_bodies_on_a_plane_take_the_terrain_replay_with_penalty_contacts(monkeypatch):
    """Under implicit_euler the stacked cubes on the plane touch it and each other in every
    step: each goes through the terrain contact replay with the penalty contacts beside its
    constraints (implicit_contact.replay's ``penalty``), which the finite-difference case
    on-floor checks."""
    from springsim.gradients import adjoints
    made = []

    class Spy(adjoints.PenaltyStep):
        def __init__(self, *args):
            super().__init__(*args)
            made.append(len(self.contacts.nodes))

    monkeypatch.setattr(adjoints, "PenaltyStep", Spy)
    gradient(on_floor(), weighted_squares, ["gravity"], duration=10 * STEPS["implicit_euler"],
             integrator="implicit_euler", dt=STEPS["implicit_euler"])
    assert len(made) == 10 and min(made) > 0   # every step, with candidate contacts


def test_concentric_balls_take_the_forwards_upward_normal_and_no_nan():
    """A ball and its partner at one point: the forward pushes them apart along +y; the
    replay's normal is the same and constant (its complex-step derivative zero), never NaN."""
    x4 = np.zeros((1, 4, 3), complex)
    x4[0, 0, 0] += 1j * stencil_geometry.STEP
    weights, normal, gap = stencil_geometry.ball_geometry(x4, None)
    assert np.array_equal(normal.real, [[0.0, 1.0, 0.0]])
    assert np.all(np.isfinite(normal)) and np.all(normal.imag == 0.0)


def test_a_replay_that_ends_elsewhere_is_refused():
    """implicit_bodies.check_solved: a step the forward took otherwise than the replay (in
    halves, which a surface carried through another makes it do, or with another active set)
    ends elsewhere; beyond a thousand CG tolerances of the speed it is refused, within passes."""
    from springsim.gradients.implicit_bodies import check_solved
    rng = np.random.default_rng(0)
    x, v = rng.normal(size=(8, 3)), rng.normal(size=(8, 3))
    h, tolerance = 0.01, 1e-5
    speed = float(np.abs(v).max())
    check_solved((x, v + 0.5e3 * tolerance * speed), (x, v), h, tolerance)
    with pytest.raises(SceneError, match="cannot follow"):
        check_solved((x, v + 2e3 * tolerance * speed), (x, v), h, tolerance)
    with pytest.raises(SceneError, match="cannot follow"):
        check_solved((x + 2e3 * h * tolerance * speed, v), (x, v), h, tolerance)
