"""Cloth: the reference's grid and springs, pinning, and a hanging cloth at rest."""
import numpy as np
import pytest

import springsim
from springsim.bodies.balls import Ball
from springsim.bodies.cloth import Cloth
from springsim.energy import kinetic_energy
from springsim.errors import SceneError
from springsim.forces import forces
from springsim.model import build_model
from springsim.scene import Scene
from springsim.springs import SpringKind
from springsim.terrains import Plane


def reference_springs(n):
    """The seed report's spring loops (index = i * n + j), transcribed: {kind: set of pairs}."""
    structural = {(i * n + j, i * n + j + 1) for i in range(n) for j in range(n - 1)}
    structural |= {(i * n + j, i * n + j + n) for i in range(n - 1) for j in range(n)}
    shear = {(i * n + j, i * n + j + n + 1) for i in range(n - 1) for j in range(n - 1)}
    shear |= {(i * n + j, i * n + j + n - 1) for i in range(n - 1) for j in range(1, n)}
    bend = {(i * n + j, i * n + j + 2) for i in range(n) for j in range(n - 2)}
    bend |= {(i * n + j, i * n + j + 2 * n) for i in range(n - 2) for j in range(n)}
    return {SpringKind.STRUCTURAL: structural, SpringKind.SHEAR: shear, SpringKind.BEND: bend}


def model_of(*bodies, **scene_settings):
    return build_model(Scene(bodies=list(bodies), **scene_settings))


def test_reference_cloth_has_1200_structural_1152_shear_1150_bend_springs():
    model = model_of(Cloth())
    assert model.particle_count == 625
    counts = {kind: model.spring_count(kind) for kind in SpringKind}
    assert counts == {SpringKind.STRUCTURAL: 1200, SpringKind.SHEAR: 1152,
                      SpringKind.BEND: 1150, SpringKind.FACE: 0}


@pytest.mark.parametrize("n", [3, 4, 7, 25])
def test_springs_are_exactly_the_reference_loops(n):
    model = model_of(Cloth(particles_per_edge=n))
    for kind, expected in reference_springs(n).items():
        pairs = model.springs[model.spring_kind == kind]
        assert {tuple(sorted(map(int, p))) for p in pairs} == expected
        assert len(pairs) == len(expected)  # each spring exactly once


def test_reference_placement_and_rest_lengths():
    model = model_of(Cloth())
    x = model.initial_positions
    np.testing.assert_allclose(x.min(axis=0), (-2.0, 0.0, -2.0))
    np.testing.assert_allclose(x.max(axis=0), (2.0, 0.0, 2.0))
    spacing = 4.0 / 24
    expected = {SpringKind.STRUCTURAL: spacing, SpringKind.SHEAR: spacing * np.sqrt(2),
                SpringKind.BEND: 2 * spacing}
    for kind, length in expected.items():
        np.testing.assert_allclose(model.arrays.rest_length[model.spring_kind == kind], length)
    assert np.all(model.mass == 1.0)
    np.testing.assert_allclose(model.arrays.drag, 3.4e-4)


def test_rotation_and_size_give_a_rigidly_moved_rectangle():
    flat = Cloth(particles_per_edge=5, width=3.0, height=1.0).particle_positions()
    turned = Cloth(particles_per_edge=5, width=3.0, height=1.0, position=(1.0, 2.0, 3.0),
                   rotation_degrees=90.0, rotation_axis=(1.0, 0.0, 0.0)).particle_positions()
    np.testing.assert_allclose(np.ptp(flat, axis=0), (3.0, 0.0, 1.0), atol=1e-12)
    # 90 degrees about x turns the local z extent into y: a vertical sheet centred at position
    np.testing.assert_allclose(np.ptp(turned, axis=0), (3.0, 1.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(turned.mean(axis=0), (1.0, 2.0, 3.0), atol=1e-12)
    pairwise = lambda p: np.linalg.norm(p[:, None] - p[None], axis=2)  # noqa: E731
    np.testing.assert_allclose(pairwise(turned), pairwise(flat), atol=1e-12)


def test_pinnings():
    n = 6
    corners = Cloth(particles_per_edge=n).pinned_mask()
    assert set(np.flatnonzero(corners)) == {0, n - 1, n * (n - 1), n * n - 1}
    edge = Cloth(particles_per_edge=n, pinned="edge")
    x = edge.particle_positions()
    pinned = np.flatnonzero(edge.pinned_mask())
    assert len(pinned) == n and np.allclose(x[pinned, 2], 2.0)  # the +z edge
    assert np.allclose(x[np.flatnonzero(Cloth(particles_per_edge=n, pinned="edge-x")
                                        .pinned_mask()), 0], -2.0)
    assert not Cloth(particles_per_edge=n, pinned="none").pinned_mask().any()
    assert set(np.flatnonzero(Cloth(particles_per_edge=n, pinned=[3, 7]).pinned_mask())) == {3, 7}


@pytest.mark.parametrize("field, value", [
    ("pinned", "sides"), ("pinned", [0, 36]), ("pinned", [1.5]), ("particles_per_edge", 1),
    ("width", 0.0), ("height", -1.0), ("particle_mass", 0.0), ("drag", -1.0),
    ("rotation_axis", (0.0, 0.0, 0.0)), ("position", (0.0, np.nan, 0.0)),
])
def test_bad_cloth_settings_are_scene_errors_naming_the_key(field, value):
    cloth = Cloth(particles_per_edge=6)
    setattr(cloth, field, value)
    with pytest.raises(SceneError) as error:
        Scene(bodies=[cloth]).validate()
    assert error.value.key == f"bodies.0.{field}"


def test_pinned_particles_never_move_even_when_a_ball_strikes_them():
    scene = springsim.load_scene("cloth-balls")
    # a fifth ball thrown straight at the pinned corner (2, 0, 2)
    scene.bodies[1].balls.append(Ball(position=(2.0, 1.0, 2.0), velocity=(0.0, -10.0, 0.0)))
    sim = springsim.Simulation(scene)
    pinned = sim.model.pinned
    start = sim.positions[pinned].copy()
    ball = sim.model.arrays.balls[-1]
    corner = np.flatnonzero(pinned)[-1]
    for _ in range(10):
        sim.advance(0.06)
        assert np.array_equal(sim.positions[pinned], start)
        assert not sim.velocities[pinned].any()
        # the corner is an immovable point: the ball (restitution 0) stops on it
        assert np.linalg.norm(sim.positions[ball] - sim.positions[corner]) > 0.95 * 0.5
    assert sim.positions[ball, 1] > 0.45


def test_hanging_cloth_settles_to_rest_in_static_equilibrium():
    # a small cloth pinned along one edge, starting flat; drag 4 N s/m on each 1 kg particle
    # removes the swinging energy the springs' dampers cannot (a rigid swing stretches nothing)
    cloth = Cloth(particles_per_edge=6, width=1.0, height=1.0, pinned="edge", drag=4.0)
    sim = springsim.Simulation(Scene(bodies=[cloth], dt=2e-4), integrator="rk4")
    peak = 0.0
    for _ in range(40):
        sim.advance(0.25)
        peak = max(peak, kinetic_energy(sim.model, sim.velocities))
    assert peak > 1.0
    assert kinetic_energy(sim.model, sim.velocities) < 1e-9 * peak
    # at rest every free particle is in force balance: springs carry its weight
    free = ~sim.model.pinned
    net = forces(sim.model.arrays, sim.positions, sim.velocities)[free]
    assert np.abs(net).max() < 1e-6 * 9.8
    # and the cloth hangs straight down from its pinned edge
    x = sim.positions
    np.testing.assert_allclose(x[free, 2], 0.5, atol=1e-6)
    assert x[free, 1].max() < -0.1


def test_a_dropped_cloth_comes_to_rest_on_a_plane_without_sinking_into_it():
    cloth = Cloth(particles_per_edge=6, width=1.0, height=1.0, pinned="none",
                  position=(0.0, 0.5, 0.0), rotation_degrees=30.0)
    plane = Plane()  # y = -1
    sim = springsim.Simulation(Scene(bodies=[cloth], terrains=[plane], dt=1e-4))
    for _ in range(35):
        sim.advance(0.1)
        assert sim.positions[:, 1].min() >= -1.0 - 1e-12
    # it lands edge first, flaps, and comes to rest flat on the plane (within the contact band)
    np.testing.assert_allclose(sim.positions[:, 1], -1.0, atol=plane.epsilon)
    assert np.abs(sim.velocities).max() < 1e-3
