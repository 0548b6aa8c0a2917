"""Attachments (attachments.py): particles of one body bound to another body's surface, hard or
soft, under every integrator: momentum kept between the two bodies, a hard binding exactly on its
triangle's point, a soft one stretched by m g / k, a seam that hangs as one cloth, bad input,
scene files and resuming."""
import numpy as np
import pytest

import springsim
from springsim.attachments import Attachment
from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.bodies.pins import Pin, Region
from springsim.errors import SceneError
from springsim.scene import Scene
from springsim.scenefile import load_scene, scene_from_table, scene_to_toml
from springsim.springs import SpringParameters

STEPS = {"explicit_euler": 1e-4, "symplectic_euler": 1e-4, "midpoint": 1e-4, "rk4": 1e-4,
         "predict_reevaluate": 1e-4, "implicit_euler": 1 / 60}
SEAM = Region(min=(-1.0, -0.1, 0.49), max=(1.0, 0.1, 0.51))   # the second panel's -z edge


def two_panels(stiffness=None, damping=0.0, **second):
    """Two 3 x 3 panels, 1 m wide, the second's -z edge on the first's +z edge, stitched;
    without drag (a cloth's own would take momentum away)."""
    first = Cloth(particles_per_edge=3, width=1.0, height=1.0, pinned="none",
                  self_collision=False, drag=0.0)
    other = Cloth(particles_per_edge=3, width=1.0, height=1.0, pinned="none",
                  self_collision=False, drag=0.0, position=(0.0, 0.0, 1.0), **second)
    stitch = Attachment(body=1, to=0, region=SEAM, stiffness=stiffness, damping=damping)
    return [first, other], [stitch]


def seam_gap(sim) -> float:
    """The largest |x_p - sum w_i x_i| over the bindings (m)."""
    arrays, x = sim.model.arrays, sim.positions
    gaps = np.einsum("aj,ajc->ac", arrays.attachment_weights, x[arrays.attachment_nodes])
    return float(np.abs(gaps).max())


def momentum(sim) -> np.ndarray:
    return (sim.model.mass[:, None] * sim.velocities).sum(axis=0)


@pytest.mark.parametrize("stiffness", [None, 40.0], ids=["hard", "soft"])
@pytest.mark.parametrize("integrator", list(STEPS))
def test_two_free_bodies_keep_their_momentum(integrator, stiffness):
    """No gravity, no terrain: the panels swing about the seam, the second thrown up and
    sideways; whatever the binding does, their total momentum stays."""
    bodies, stitch = two_panels(stiffness, damping=0.5 if stiffness else 0.0,
                                velocity=(0.3, 1.0, 0.0))
    bodies[1].position = (0.0, 0.02, 1.0)   # a soft seam starts open: its springs pull
    scene = Scene(bodies=bodies, attachments=stitch, gravity=(0.0, 0.0, 0.0),
                  integrator=integrator, dt=STEPS[integrator])
    scene.validate()
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    start = momentum(sim)
    sim.step(30 if integrator == "implicit_euler" else 600)
    assert np.abs(momentum(sim) - start).max() < 1e-12
    assert np.abs(sim.velocities).max() > 0.1   # it moved
    if stiffness is None:
        assert seam_gap(sim) < 1e-12


@pytest.mark.parametrize("integrator", list(STEPS))
def test_a_hard_binding_is_on_its_point_at_every_step(integrator):
    """One particle of a small panel bound to the middle of a triangle of a falling, spinning
    panel: exactly on its barycentric point after every step, from the start."""
    base = Cloth(particles_per_edge=3, width=1.0, height=1.0, pinned="none",
                 self_collision=False, velocity=(0.0, 0.5, 0.0))
    flap = Cloth(particles_per_edge=2, width=0.2, height=0.2, pinned="none",
                 self_collision=False, bend=SpringParameters(0.0, 0.0),
                 position=(0.27, 0.03, 0.22))
    scene = Scene(bodies=[base, flap], attachments=[Attachment(body=1, to=0, particles=[0])],
                  integrator=integrator, dt=STEPS[integrator])
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    weights = sim.model.arrays.attachment_weights[0]
    assert np.all(-weights[1:] > 0.05)   # inside the triangle, not on an edge
    worst = seam_gap(sim)
    for _ in range(20):
        sim.step(1 if integrator == "implicit_euler" else 20)
        worst = max(worst, seam_gap(sim))
    assert worst < 1e-14
    assert np.abs(sim.positions - sim.model.initial_positions).max() > 0.01   # it moved


@pytest.mark.parametrize("integrator", ["symplectic_euler", "implicit_euler"])
def test_a_soft_binding_stretches_by_m_g_over_k(integrator):
    """A light panel under a pinned one, each particle on a soft binding of k = 100 N/m: it
    sags by m g / k (its own springs unstretched, the pinned panel unmoved)."""
    holder = Cloth(particles_per_edge=3, width=1.0, height=1.0, pinned="none",
                   self_collision=False,
                   pins=[Pin(region=Region(min=(-1, -1, -1), max=(1, 1, 1)))])
    weight = Cloth(particles_per_edge=2, width=0.4, height=0.4, pinned="none",
                   self_collision=False,
                   bend=SpringParameters(0.0, 0.0), particle_mass=0.1)
    bind = Attachment(body=1, to=0, particles=[0, 1, 2, 3], stiffness=100.0, damping=2.0)
    scene = Scene(bodies=[holder, weight], attachments=[bind], integrator=integrator,
                  dt=STEPS[integrator])
    sim = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    sim.advance(3.0)
    assert sim.positions[9:, 1] == pytest.approx(-0.1 * 9.8 / 100.0, rel=1e-4)
    assert np.array_equal(sim.positions[:9], sim.model.initial_positions[:9])


def test_two_panels_stitched_along_an_edge_hang_as_one():
    """The first panel pinned along its -z edge, the second stitched to its +z edge: together
    they hang straight down, 2 m, the seam closed."""
    bodies, stitch = two_panels()
    bodies[0].pinned = "edge-z"
    scene = Scene(bodies=bodies, attachments=stitch, integrator="implicit_euler", dt=1 / 60,
                  drag=0.05)
    sim = springsim.Simulation(scene, integrator="implicit_euler", dt=1 / 60)
    sim.advance(4.0)
    assert seam_gap(sim) < 1e-12
    free_edge = sim.positions[9 + 6:]   # the second panel's +z row
    assert free_edge[:, 1] == pytest.approx(-2.0, abs=0.1)
    assert np.abs(free_edge[:, 2] + 0.5).max() < 0.1


def test_a_seam_is_not_a_contact():
    """Bodies an attachment joins are one contact body: the seam, where the surfaces touch,
    pushes nothing apart."""
    bodies, stitch = two_panels()
    joined = springsim.Simulation(Scene(bodies=bodies, attachments=stitch), dt=1e-4)
    assert len(joined.model.arrays.surface_triangles) == 0   # no two bodies left to touch
    apart = springsim.Simulation(Scene(bodies=bodies), dt=1e-4)
    assert len(apart.model.arrays.surface_triangles) > 0


@pytest.mark.parametrize("integrator", ["rk4", "implicit_euler"])
def test_resuming_from_a_saved_state_is_bit_identical(integrator, tmp_path):
    bodies, stitch = two_panels(stiffness=200.0, damping=1.0)
    bodies[0].pinned = "edge-z"
    scene = Scene(bodies=bodies, attachments=stitch, integrator=integrator,
                  dt=STEPS[integrator])
    whole = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    whole.step(40)
    half = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    half.step(20)
    half.save_state(tmp_path / "state.npz")
    resumed = springsim.Simulation(scene, integrator=integrator, dt=STEPS[integrator])
    resumed.load_state(tmp_path / "state.npz")
    resumed.step(20)
    assert np.array_equal(resumed.positions, whole.positions)
    assert np.array_equal(resumed.velocities, whole.velocities)


def test_a_scene_file_says_attachments_and_writes_them_back(tmp_path):
    path = tmp_path / "stitched.toml"
    path.write_text("""dt = 0.001
[[bodies]]
type = "cloth"
particles_per_edge = 3
width = 1.0
height = 1.0
[[bodies]]
type = "cloth"
particles_per_edge = 3
width = 1.0
height = 1.0
position = [0.0, 0.0, 1.0]
[[attachments]]
body = 1
to = 0
stiffness = 500.0
[attachments.region]
min = [-1.0, -0.1, 0.49]
max = [1.0, 0.1, 0.51]
""")
    scene = load_scene(path, ["attachments.0.damping=2.5"])
    attachment = scene.attachments[0]
    assert (attachment.body, attachment.to, attachment.stiffness) == (1, 0, 500.0)
    assert attachment.damping == 2.5 and attachment.distance == 0.05
    again = tmp_path / "again.toml"
    again.write_text(scene_to_toml(scene))
    assert load_scene(again).attachments == scene.attachments
    assert load_scene(again.with_name("again.toml")).attachments[0].region.max == (1.0, 0.1,
                                                                                    0.51)


def balls_and_cloth(attachment):
    ball = Balls(balls=[Ball(position=(0.0, -0.5, 0.0))])
    return Scene(bodies=[Cloth(particles_per_edge=3), ball], attachments=[attachment],
                 dt=1e-4)


@pytest.mark.parametrize("attachment, key, words", [
    (Attachment(body=1, to=3, particles=[0]), "attachments.0.to", "[0, 1]"),
    (Attachment(body=-1, to=0, particles=[0]), "attachments.0.body", "body number"),
    (Attachment(body=0, to=0, particles=[0]), "attachments.0.to", "another body"),
    (Attachment(body=1, to=0), "attachments.0", "exactly one way"),
    (Attachment(body=1, to=0, particles=[0], stiffness=-5.0), "attachments.0.stiffness", "> 0"),
    (Attachment(body=1, to=0, particles=[0], damping=-1.0), "attachments.0.damping", ">= 0"),
    (Attachment(body=1, to=0, particles=[0], distance=0.0), "attachments.0.distance", "> 0"),
])
def test_bad_attachments_are_one_line_naming_the_key(attachment, key, words):
    with pytest.raises(SceneError) as raised:
        balls_and_cloth(attachment).validate()
    assert raised.value.key == key and words in str(raised.value)
    assert "\n" not in str(raised.value)


@pytest.mark.parametrize("attachment, key, words", [
    (Attachment(body=1, to=0, region=Region(min=(5, 5, 5), max=(6, 6, 6))), "attachments.0",
     "chooses no particle"),
    (Attachment(body=1, to=0, particles=[3]), "attachments.0.particles", "[0, 0]"),
    (Attachment(body=1, to=0, particles=[0]), "attachments.0.distance", "0.5 m from"),
    (Attachment(body=0, to=1, particles=[0]), "attachments.0.to", "without surface"),
])
def test_attachments_that_cannot_bind_are_refused_before_a_step(attachment, key, words):
    scene = balls_and_cloth(attachment)
    scene.validate()
    with pytest.raises(SceneError) as raised:
        springsim.Simulation(scene, dt=1e-4)
    assert raised.value.key == key and words in str(raised.value)
    assert "\n" not in str(raised.value)


def test_nearest_triangles_agree_with_a_search_of_every_pair():
    """attachments.nearest_triangles (libigl's tree) against every point-triangle pair: the
    same distances, and weights that give a point of the chosen triangle at that distance."""
    import trimesh

    from springsim.attachments import nearest_triangles
    from springsim.geometry.closest_points import closest_on_triangle

    sphere = trimesh.creation.icosphere(subdivisions=3, radius=1.0)
    corners = np.ascontiguousarray(sphere.vertices[sphere.faces], float)
    points = np.random.default_rng(4).uniform(-1.5, 1.5, (60, 3))
    row, weights, gap = nearest_triangles(points, corners)
    for i, p in enumerate(points):
        nearest = min(np.linalg.norm(p - np.dot(closest_on_triangle(p, triangle), triangle))
                      for triangle in corners)
        assert gap[i] == pytest.approx(nearest, rel=1e-12, abs=1e-14)
        on_triangle = weights[i] @ corners[row[i]]
        assert np.linalg.norm(p - on_triangle) == pytest.approx(gap[i], rel=1e-12, abs=1e-14)
        assert weights[i].min() >= 0.0 and weights[i].sum() == pytest.approx(1.0)
