"""Backward Euler (implicit_euler): its Jacobians against finite differences, the matrix and its
conjugate-gradient solve against SciPy, convergence of the Newton iterations to the backward-Euler
equations, energy, contact (no push into a terrain, Coulomb sliding and sticking, restitution),
pins, and the large-step bars of the four jelly scenes at dt = 1/30 s."""
import numpy as np
import pytest
import scipy.sparse
import scipy.sparse.linalg

from conftest import EARTH_GRAVITY, build_cube_simulation, perturb
from springsim import SceneError, Simulation
from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.bodies.cloth_material import ClothMaterial
from springsim.bodies.cube import Cube
from springsim.collision.contact_sets.solve import no_contacts
from springsim.implicit.cg import CGWork, filtered_cg, search_product
from springsim.implicit.constraints import CONTACT, FREE, PINNED, SLIP_SPEED
from springsim.implicit.jacobian import assemble_diagonal_and_terms, assemble_system
from springsim.implicit.pattern import build_block_pattern, build_solve_layout
from springsim.implicit.spring_terms import spring_terms_like
from springsim.collision.pair_lists import no_pair_list
from springsim.collision.pair_lists.solve_pairs import kept_surface_pairs
from springsim.integrators import get_integrator
from springsim.integrators.implicit_euler import (ImplicitState, Scratch, Settings, Statistics,
                                                  backward_euler_step, saved_state, workspace)
from springsim.implicit.step_record import no_record
from springsim.presets import preset
from springsim.reference import reference_forces
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.terrains import Plane, Sphere, tilted_plane

H = 1.0 / 30.0   # s, a step per 30 Hz frame


def stiff_cube(**options):
    """A 3 x 3 x 3 cube, 1 m edge, with the course's stiffness and damping (2000 N/m, 60 N s/m)
    and some drag, centred at the origin."""
    return build_cube_simulation("implicit_euler", H, ks=2000.0, kd=60.0, drag=0.3, **options)


def dense(simulation, mass_scale, damping_scale, stiffness_scale, x=None):
    """The assembled matrix as a dense (3P, 3P) array."""
    pattern = build_block_pattern(simulation.model.arrays)
    blocks = np.empty((pattern.block_count, 3, 3))
    assemble_system(simulation.model.arrays, pattern,
                    simulation.positions if x is None else x,
                    mass_scale, damping_scale, stiffness_scale, blocks)
    return scipy.sparse.bsr_matrix((blocks, pattern.column, pattern.row_start)).toarray()


def force_jacobian(simulation, x, v, wrt, step=1e-6):
    """dF/dx or dF/dv of the NumPy reference forces by central differences, (3P, 3P)."""
    base = (x, v)[wrt == "v"]
    columns = []
    for k in range(base.size):
        shift = np.zeros(base.size)
        shift[k] = step
        shift = shift.reshape(base.shape)
        if wrt == "x":
            plus = reference_forces(simulation.model, x + shift, v)
            minus = reference_forces(simulation.model, x - shift, v)
        else:
            plus = reference_forces(simulation.model, x, v + shift)
            minus = reference_forces(simulation.model, x, v - shift)
        columns.append(((plus - minus) / (2 * step)).ravel())
    return np.array(columns).T


def scaled_cube(factor, seed=0):
    """The stiff cube with every spring ``factor`` times its rest length (plus a little noise,
    far smaller than the stretch), moving rigidly: no damper is stretching."""
    simulation = stiff_cube()
    x = simulation.state.positions
    rng = np.random.default_rng(seed)
    x[:] = factor * x + 0.005 * rng.standard_normal(x.shape)
    simulation.state.velocities[:] = (0.3, -0.2, 0.1)
    return simulation


def test_stiffness_jacobian_of_stretched_springs_matches_finite_differences():
    simulation = scaled_cube(1.1)
    x, v = simulation.positions, simulation.velocities
    expected = force_jacobian(simulation, x, v, "x")
    assert np.allclose(-dense(simulation, 0.0, 0.0, 1.0), expected, atol=1e-4 * 2000.0)


def test_damper_jacobian_matches_finite_differences():
    simulation = stiff_cube(perturb_seed=2)
    x, v = simulation.positions, simulation.velocities
    expected = force_jacobian(simulation, x, v, "v")   # dampers and drag
    assert np.allclose(-dense(simulation, 0.0, 1.0, 0.0), expected, atol=1e-6 * 60.0)


def test_compressed_springs_lose_exactly_their_transverse_stiffness():
    simulation = scaled_cube(0.9)
    x, v = simulation.positions, simulation.velocities
    arrays = simulation.model.arrays
    # what is dropped: -ks (1 - r/L)(I - l l^T) on (a, a) and (b, b), the opposite on (a, b), (b, a)
    dropped = np.zeros((x.size, x.size))
    for (a, b), rest, group in zip(arrays.springs, arrays.rest_length, arrays.spring_group):
        d = x[a] - x[b]
        length = np.linalg.norm(d)
        assert length < rest
        l = d / length
        block = -arrays.group_ks[group] * (1 - rest / length) * (np.eye(3) - np.outer(l, l))
        for row, column, sign in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
            dropped[3 * row:3 * row + 3, 3 * column:3 * column + 3] += sign * block
    expected = force_jacobian(simulation, x, v, "x") - dropped
    assert np.allclose(-dense(simulation, 0.0, 0.0, 1.0), expected, atol=1e-4 * 2000.0)


@pytest.mark.parametrize("squeeze", [0.6, 1.0, 1.3])
def test_system_matrix_is_symmetric_positive_definite(squeeze):
    simulation = stiff_cube()
    perturb(simulation, seed=4, squeeze=squeeze, jitter=0.1)
    matrix = dense(simulation, 1.0, H, H * H)
    assert np.array_equal(matrix, matrix.T)
    assert np.linalg.eigvalsh(matrix).min() > 0.5   # at least the 1 kg mass


@pytest.mark.parametrize("tolerance", [1e-4, 1e-9])
def test_cg_meets_the_requested_residual_and_agrees_with_a_direct_solve(tolerance):
    simulation = stiff_cube(pinned=(0, 8, 26))
    perturb(simulation, seed=5, squeeze=0.8, jitter=0.05)
    arrays, count = simulation.model.arrays, simulation.model.particle_count
    pattern = build_block_pattern(arrays)
    blocks = np.empty((pattern.block_count, 3, 3))
    assemble_system(arrays, pattern, simulation.positions, 1.0, H, H * H, blocks)
    b = np.random.default_rng(6).standard_normal((count, 3))
    kind = np.where(simulation.model.pinned, PINNED, FREE).astype(np.int8)
    normal = np.zeros((count, 3))
    u = np.zeros((count, 3))
    work = [np.zeros((count, 3)) for _ in range(4)]
    filtered_cg(pattern, blocks, b, kind, normal, u, tolerance, 1000, CGWork(*work))

    matrix = scipy.sparse.bsr_matrix((blocks, pattern.column, pattern.row_start)).tocsr()
    free = np.repeat(kind == FREE, 3)
    residual = (b.ravel() - matrix @ u.ravel())[free]
    assert np.linalg.norm(residual) <= tolerance * np.linalg.norm(b.ravel()[free])
    assert np.all(u[kind == PINNED] == 0.0)
    direct = scipy.sparse.linalg.spsolve(matrix[free][:, free].tocsc(), b.ravel()[free])
    assert np.linalg.norm(u.ravel()[free] - direct) <= 10 * tolerance * np.linalg.norm(direct)


def material_cloth():
    """A 12 x 12 cloth of a material: its border springs' constants differ from the inner ones',
    which cuts the force loop's runs (one group each) short."""
    cloth = Cloth(particles_per_edge=12, width=0.5, height=0.8, pinned="corners",
                  material=ClothMaterial())
    return Simulation(Scene(name="material", bodies=[cloth], integrator="implicit_euler",
                            dt=1 / 60))


@pytest.mark.parametrize("made", [lambda: stiff_cube(pinned=(0, 8)), material_cloth],
                         ids=["cube", "material cloth"])
def test_the_fused_search_product_is_the_filtered_product_of_the_assembled_matrix(made):
    """cg.search_product makes c = s + beta c and q = S A c from the diagonal blocks and the
    springs' terms in three passes: the same as the full assembled
    matrix (SciPy) times c, filtered, to rounding; and it returns c . q."""
    simulation = made()
    perturb(simulation, seed=11, squeeze=0.9, jitter=0.05)
    arrays, x = simulation.model.arrays, simulation.positions
    count = simulation.model.particle_count
    layout = build_solve_layout(arrays)
    assert len(layout.runs) > 0   # the fused path
    # the solve's runs take every spring whatever its constants: a lattice's springs all run
    assert len(layout.loose_pairs) == 0 and len(layout.runs) <= len(arrays.spring_runs)
    blocks = np.empty((count, 3, 3))
    terms = spring_terms_like(layout.runs, layout.run_entries, layout.loose_pairs, x)
    assemble_diagonal_and_terms(arrays, layout, x, 1.0, H, H * H, blocks, terms)
    full = build_block_pattern(arrays)
    full_blocks = np.empty((full.block_count, 3, 3))
    assemble_system(arrays, full, x, 1.0, H, H * H, full_blocks)
    matrix = scipy.sparse.bsr_matrix((full_blocks, full.column, full.row_start)).tocsr()

    rng = np.random.default_rng(12)
    kind = np.where(simulation.model.pinned, PINNED, FREE).astype(np.int8)
    kind[[3, 13]] = CONTACT
    normal = np.zeros((count, 3))
    normal[[3, 13]] = (0.0, 1.0, 0.0)
    s, c = rng.standard_normal((count, 3)), rng.standard_normal((count, 3))
    q = np.empty((count, 3))
    expected_c = s + 0.7 * c
    curvature = search_product(layout.diagonal, blocks, terms, no_contacts(), kind, normal,
                               s, 0.7, c, q)
    expected_q = (matrix @ expected_c.ravel()).reshape(-1, 3)
    expected_q[kind == PINNED] = 0.0
    expected_q[kind == CONTACT, 1] = 0.0
    assert np.allclose(c, expected_c, rtol=0, atol=1e-15)   # to rounding (fused multiply-add)
    assert np.allclose(q, expected_q, rtol=0, atol=1e-12 * np.abs(matrix).max())
    assert curvature == pytest.approx(np.sum(c * q), rel=1e-12)


def test_cg_leaves_the_normal_components_of_contacts_where_they_start():
    simulation = stiff_cube(perturb_seed=7)
    arrays, count = simulation.model.arrays, simulation.model.particle_count
    pattern = build_block_pattern(arrays)
    blocks = np.empty((pattern.block_count, 3, 3))
    assemble_system(arrays, pattern, simulation.positions, 1.0, H, H * H, blocks)
    rng = np.random.default_rng(8)
    b = rng.standard_normal((count, 3))
    kind = np.full(count, FREE, np.int8)
    kind[::3] = CONTACT
    normal = rng.standard_normal((count, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    start = rng.standard_normal((count, 3))
    u = start.copy()
    work = [np.zeros((count, 3)) for _ in range(4)]
    filtered_cg(pattern, blocks, b, kind, normal, u, 1e-10, 1000, CGWork(*work))

    contact = kind == CONTACT
    assert np.allclose(np.einsum("ij,ij->i", u - start, normal)[contact], 0.0, atol=1e-12)
    matrix = scipy.sparse.bsr_matrix((blocks, pattern.column, pattern.row_start)).tocsr()
    residual = (b.ravel() - matrix @ u.ravel()).reshape(-1, 3)
    residual[contact] -= np.einsum("ij,ij->i", residual, normal)[contact, None] * normal[contact]
    start_residual = (b.ravel() - matrix @ start.ravel()).reshape(-1, 3)
    start_residual[contact] -= (np.einsum("ij,ij->i", start_residual, normal)[contact, None]
                                * normal[contact])
    assert np.linalg.norm(residual) <= 1e-10 * np.linalg.norm(start_residual)


def test_cg_has_nothing_to_solve_for_a_load_the_constraints_carry():
    """b along the contact normals only, as under a resting body: filtering it leaves ~1e-17 of
    rounding, which a goal relative to that starting residual would chase (to max_iterations,
    or with huge steps along rounding into the contacts)."""
    simulation = stiff_cube(perturb_seed=7)
    arrays, count = simulation.model.arrays, simulation.model.particle_count
    pattern = build_block_pattern(arrays)
    blocks = np.empty((pattern.block_count, 3, 3))
    assemble_system(arrays, pattern, simulation.positions, 1.0, H, H * H, blocks)
    rng = np.random.default_rng(9)
    kind = np.full(count, FREE, np.int8)
    kind[::3] = CONTACT
    normal = rng.standard_normal((count, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    b = np.where((kind == CONTACT)[:, None], rng.uniform(0.1, 1.0, (count, 1)) * normal, 0.0)
    u = np.zeros((count, 3))
    work = [np.zeros((count, 3)) for _ in range(4)]
    iterations, reference = filtered_cg(pattern, blocks, b, kind, normal, u, 1e-5, 1000,
                                        CGWork(*work))
    assert iterations == 0
    assert reference == pytest.approx(np.linalg.norm(b))
    assert np.all(u == 0.0)


def test_newton_iterations_converge_to_the_backward_euler_step():
    """The residual of M (v' - v) = h F(x + h v', v') shrinks with every Newton iteration."""
    residuals = []
    for iterations in (1, 2, 3, 5):
        springs = SpringParameters(2000.0, 5.0)
        scene = Scene(name="newton", bodies=[Cube(particles_per_edge=3, edge_length=1.0,
                                                  position=(0.0, 0.0, 0.0), structural=springs,
                                                  shear=springs, bend=springs)],
                      gravity=EARTH_GRAVITY)
        simulation = Simulation(scene, integrator="implicit_euler", dt=H,
                                newton_iterations=iterations, cg_tolerance=1e-12,
                                cg_max_iterations=10000)
        perturb(simulation, seed=3, squeeze=0.7, jitter=0.05)
        x, v = simulation.positions.copy(), simulation.velocities.copy()
        simulation.step(1)
        assert np.allclose(simulation.positions, x + H * simulation.velocities, atol=1e-14)
        mass = simulation.model.mass[:, None]
        new_v = simulation.velocities
        residual = mass * (new_v - v) - H * reference_forces(simulation.model, x + H * new_v,
                                                             new_v)
        residuals.append(np.abs(residual).max())
    assert all(later < earlier for earlier, later in zip(residuals, residuals[1:])), residuals
    assert residuals[-1] < 1e-2 * residuals[0], residuals


@pytest.mark.parametrize("gravity", [(0.0, 0.0, 0.0), EARTH_GRAVITY])
def test_energy_never_increases_without_damping(gravity):
    simulation = build_cube_simulation("implicit_euler", H, gravity=gravity, ks=50.0, kd=0.0,
                                       perturb_seed=1, particles_per_edge=4)
    energies = [simulation.energy()["total"]]
    for _ in range(90):
        simulation.step(1)
        energies.append(simulation.energy()["total"])
    assert np.all(np.diff(energies) <= 1e-12 * abs(energies[0]))
    assert energies[-1] < energies[0]   # backward Euler damps: it does not just hold


def resting_cube(dt=H, friction=0.3):
    """The course's cube springs, 4 per edge and 1 m edge, placed with its lowest layer 1 mm
    above the plane y = -1 (inside the 1 cm contact band), at rest."""
    springs = SpringParameters(2000.0, 60.0)
    cube = Cube(particles_per_edge=4, edge_length=1.0, position=(0.0, 0.0, 0.0),
                structural=springs, shear=springs, bend=springs)
    scene = Scene(name="rest", bodies=[cube], terrains=[Plane(friction=friction)],
                  gravity=EARTH_GRAVITY)
    simulation = Simulation(scene, integrator="implicit_euler", dt=dt)
    simulation.state.positions[:, 1] += -0.999 - simulation.positions[:, 1].min()
    return simulation


def test_cube_resting_on_the_plane_stays_at_rest():
    simulation = resting_cube()
    start = simulation.positions.mean(axis=0)
    simulation.advance(3.0)   # sagging into its static equilibrium
    settled = simulation.positions.copy()
    simulation.advance(3.0)
    assert np.abs(simulation.positions - settled).max() < 1e-5
    assert np.abs(simulation.velocities).max() < 1e-5
    # static equilibrium: every particle off the plane feels no net force, every one on it is
    # pushed into the plane within the friction cone
    force = reference_forces(simulation.model, simulation.positions, simulation.velocities)
    height = simulation.positions[:, 1] + 1.0
    assert height.min() >= 0.0
    on_plane = height < 0.01
    weight = 9.8
    assert np.abs(force[~on_plane]).max() < 1e-3 * weight
    assert np.all(force[on_plane, 1] < 0.0)
    sideways = np.linalg.norm(force[on_plane][:, [0, 2]], axis=1)
    assert np.all(sideways <= 0.3 * -force[on_plane, 1] + 1e-3 * weight)
    # the centre of mass has not drifted sideways
    assert np.abs(simulation.positions.mean(axis=0) - start)[[0, 2]].max() < 1e-9


def sliding_cube(degrees, friction, integrator="implicit_euler", dt=H, **options):
    """The course's springs, 4 per edge, turned about z so that a face lies on a plane through
    the origin sloping ``degrees`` down towards +x, 1 mm above it, at rest (``options``: the
    integrator's)."""
    springs = SpringParameters(2000.0, 60.0)
    angle = np.radians(degrees)
    normal = np.array([np.sin(angle), np.cos(angle), 0.0])
    cube = Cube(particles_per_edge=4, edge_length=1.0, position=tuple(2.0 * normal),
                rotation_degrees=-float(degrees), rotation_axis=(0.0, 0.0, 1.0),
                structural=springs, shear=springs, bend=springs)
    slope = Plane(point=(0.0, 0.0, 0.0), normal=tuple(normal), friction=friction)
    scene = Scene(name="slide", bodies=[cube], terrains=[slope], gravity=EARTH_GRAVITY)
    simulation = Simulation(scene, integrator=integrator, dt=dt, **options)
    phi = simulation.positions @ normal
    simulation.state.positions += (0.001 - phi.min()) * normal
    return simulation, np.array([np.cos(angle), -np.sin(angle), 0.0])


def mean_velocity(simulation):
    mass = simulation.model.mass[:, None]
    return (mass * simulation.velocities).sum(axis=0) / mass.sum()


@pytest.mark.parametrize("degrees, friction", [(45, 0.3), (30, 0.3), (30, 0.8)])
def test_cube_on_a_slope_slides_with_coulomb_friction_or_sticks(degrees, friction):
    """The centre of mass accelerates down the slope at g (sin a - mu cos a) when mu < tan a,
    and the cube stays put when mu > tan a (at 30 degrees it cannot tip over either)."""
    simulation, downhill = sliding_cube(degrees, friction)
    simulation.advance(1.0)
    speed_before = mean_velocity(simulation) @ downhill
    simulation.advance(1.0)
    acceleration = mean_velocity(simulation) @ downhill - speed_before
    angle = np.radians(degrees)
    expected = max(0.0, 9.8 * (np.sin(angle) - friction * np.cos(angle)))
    assert acceleration == pytest.approx(expected, abs=0.01 * 9.8)
    if expected == 0.0:
        assert np.abs(simulation.velocities).max() < 1e-5


SQRT_HALF = np.sqrt(0.5)


@pytest.mark.parametrize("terrain, surface_point, normal", [
    (Plane(), (0.0, -1.0, 0.0), (0.0, 1.0, 0.0)),
    (tilted_plane(), (0.0, 0.0, 0.0), (SQRT_HALF, SQRT_HALF, 0.0)),
    (Sphere(), (0.0, 2.0, 0.0), (0.0, 1.0, 0.0)),
], ids=["plane", "tilted", "sphere"])
def test_the_solve_never_moves_a_particle_into_a_terrain(terrain, surface_point, normal):
    """Steps taken without the impact pass that lifts particles out: a cube thrown at a terrain
    at 15 m/s (0.5 m per step, and sideways) ends every step on or outside it."""
    normal = np.asarray(normal)
    springs = SpringParameters(2000.0, 60.0)
    cube = Cube(particles_per_edge=4, edge_length=1.0,
                position=tuple(np.asarray(surface_point) + 2.5 * normal),
                velocity=tuple(-15.0 * normal + np.array([0.0, 0.0, 3.0])), structural=springs,
                shear=springs, bend=springs)
    scene = Scene(name="throw", bodies=[cube], terrains=[terrain], gravity=EARTH_GRAVITY)
    simulation = Simulation(scene, integrator="implicit_euler", dt=H)
    arrays = simulation.model.arrays
    layout = simulation.integrator.pattern(simulation.model)
    state = ImplicitState(simulation.positions, simulation.velocities, simulation.state.contacts)
    work = workspace(layout, simulation.positions, arrays.terrain_epsilon.shape[0])
    scratch = Scratch(layout, Settings(1, 1e-8, 1000), work,
                      kept_surface_pairs(simulation.positions), Statistics.zeros(),
                      saved_state(state), saved_state(state), no_record())
    no_pairs = no_pair_list()   # no self-colliding surface: no pair of one body for the solve
    touched = False
    for _ in range(12):
        backward_euler_step(arrays, state, scratch, H, no_pairs)
        depth = -terrain.signed_distance(simulation.positions).min()
        assert depth <= 1e-9
        touched |= depth > -0.01
    assert touched


def ball_on_the_tilted_plane(friction, dt):
    """A 1 kg ball of radius 0.1 m touching the tilted plane (phi = 0, rounded up: 1e-17 m
    inside, the scene would be refused), at rest."""
    plane = tilted_plane(friction=friction)
    radius = 0.1
    offset = radius * SQRT_HALF
    while plane.signed_distance(np.array([offset, offset, 0.0]), radius) < 0.0:
        offset = np.nextafter(offset, 1.0)
    ball = Ball(position=(offset, offset, 0.0), radius=radius, mass=1.0)
    scene = Scene(name="ball", bodies=[Balls(balls=[ball])], terrains=[plane],
                  gravity=EARTH_GRAVITY)
    return Simulation(scene, integrator="implicit_euler", dt=dt), plane


@pytest.mark.parametrize("dt", [0.01, H])
def test_ball_that_friction_holds_on_a_slope_stays_put(dt):
    """Friction 1.2 > tan 45: for 2 s the ball creeps no faster than SLIP_SPEED (regularized
    friction, constraints.py), so it moves at most SLIP_SPEED * 2 s. Once, at some steps the
    solve's rounding pushed it into the plane: the contact was released, friction was lost,
    and the velocity jumped to g sin 45 dt."""
    simulation, plane = ball_on_the_tilted_plane(1.2, dt)
    start = simulation.positions.copy()
    steps = round(2.0 / dt)
    for _ in range(steps):
        simulation.step(1)
        assert np.linalg.norm(simulation.velocities) <= SLIP_SPEED
    assert np.linalg.norm(simulation.positions - start) <= SLIP_SPEED * steps * dt
    assert plane.signed_distance(simulation.positions, 0.1).min() > -1e-12


@pytest.mark.parametrize("dt", [0.01, H])
def test_ball_on_a_slope_slides_at_the_coulomb_acceleration(dt):
    """Friction 0.3 < tan 45: the ball slides down at g (sin 45 - 0.3 cos 45), on the plane."""
    simulation, plane = ball_on_the_tilted_plane(0.3, dt)
    downhill = np.array([1.0, -1.0, 0.0]) * SQRT_HALF
    expected = 9.8 * SQRT_HALF * (1.0 - 0.3)
    simulation.step(1)
    # constant forces: one backward Euler step is exact, but for the ball's drag (3.4e-4 N s/m)
    assert np.allclose(simulation.velocities[0], expected * dt * downhill, rtol=0.0,
                       atol=1e-5 * expected * dt)
    first = simulation.velocities[0] @ downhill
    steps = round(2.0 / dt) - 1
    simulation.step(steps)
    # 1%: the friction damper of a step comes from the last step's slip, slower by a dt, which
    # adds up to ~0.3% too much friction (and the drag ~0.05%)
    acceleration = (simulation.velocities[0] @ downhill - first) / (steps * dt)
    assert acceleration == pytest.approx(expected, rel=0.01)
    assert abs(simulation.velocities[0] @ plane.unit_normal()) < 1e-9
    assert abs(simulation.velocities[0, 2]) == 0.0


def first_bounce(simulation) -> float:
    """Step a lone ball until it first moves up; returns its vertical speed in the step before,
    the speed it arrived with."""
    while True:
        approach = simulation.velocities[0, 1]
        simulation.step(1)
        if simulation.velocities[0, 1] > 0.0:
            return approach


def test_restitution_reflects_the_approach_speed():
    """A ball dropped 2.5 m onto the plane leaves it at e times the speed it came in with, even
    at a step that carries it 0.1 m past the surface; as dt shrinks that speed tends to
    sqrt(2 g 2.5) m/s."""
    for dt, tolerance in ((1 / 60, 0.05), (1e-3, 0.005)):
        ball = Ball(position=(0.0, 2.0, 0.0), radius=0.5, mass=1.0)
        scene = Scene(name="ball", bodies=[Balls(balls=[ball])], terrains=[Plane()],
                      gravity=EARTH_GRAVITY)
        simulation = Simulation(scene, integrator="implicit_euler", dt=dt)
        approach = first_bounce(simulation)
        # e times the approach speed, up to the one step of gravity the impact step adds
        assert abs(simulation.velocities[0, 1] + 0.8 * approach) <= 0.8 * 9.8 * dt * (1 + 1e-9)
        assert -approach == pytest.approx(np.sqrt(2 * 9.8 * 2.5), rel=tolerance)


def test_pinned_particles_stay_fixed():
    top = tuple(range(2, 27, 3))   # the nine particles (i, j, 2): one face of the cube
    simulation = build_cube_simulation("implicit_euler", H, gravity=EARTH_GRAVITY, ks=2000.0,
                                       kd=60.0, pinned=top)
    pinned = simulation.model.pinned
    start = simulation.positions.copy()
    simulation.advance(3.0)
    assert np.array_equal(simulation.positions[pinned], start[pinned])
    assert np.all(simulation.velocities[pinned] == 0.0)
    assert np.abs(simulation.positions[~pinned] - start[~pinned]).max() > 1e-3   # it sags


def test_options_reach_the_integrator_and_bad_ones_are_refused():
    simulation = resting_cube()
    assert simulation.integrator.newton_iterations == 1
    simulation = Simulation(resting_cube().scene, integrator="implicit_euler", dt=H,
                            newton_iterations=2, cg_tolerance=1e-7, cg_max_iterations=50)
    assert (simulation.integrator.newton_iterations, simulation.integrator.cg_tolerance,
            simulation.integrator.cg_max_iterations) == (2, 1e-7, 50)
    for options in ({"newton_iterations": 0}, {"newton_iterations": 1.5},
                    {"newton_iterations": True}, {"cg_tolerance": 0.0}, {"cg_tolerance": 1.0},
                    {"cg_tolerance": float("nan")}, {"cg_max_iterations": 0},
                    {"preconditioner": "ilu"}):
        with pytest.raises(SceneError) as error:
            get_integrator("implicit_euler", **options)
        assert next(iter(options)) in str(error.value)


def centre_jacobians(x, n):
    """det of the lattice's Jacobian at every cell centre (averaged edges): negative when the
    cell is inverted, near zero when it has collapsed."""
    g = x.reshape(n, n, n, 3)

    def edges(axis):
        e = np.diff(g, axis=axis)
        others = [a for a in range(3) if a != axis]
        for a in others:
            e = 0.5 * (np.take(e, range(n - 1), axis=a) + np.take(e, range(1, n), axis=a))
        return e

    return np.einsum("...i,...i", np.cross(edges(0), edges(1)), edges(2))


@pytest.mark.parametrize("scene", ["jelly-plane", "jelly-tilted", "jelly-sphere", "jelly-bowl"])
def test_jelly_scenes_at_a_30_hz_step(scene):
    """The default cube, 10 s at dt = 1/30 s: no divergence, penetration at most epsilon, no
    inverted or collapsed cell, and the ending each scene calls for."""
    simulation = Simulation(preset(scene), integrator="implicit_euler", dt=H)
    terrain = simulation.model.terrains[0]
    rest_volume = centre_jacobians(simulation.positions, 10).min()
    smallest = np.inf
    velocities = {}
    for step in range(300):
        simulation.step(1)   # raises SimulationDiverged on divergence
        assert -terrain.signed_distance(simulation.positions).min() <= terrain.epsilon
        smallest = min(smallest, centre_jacobians(simulation.positions, 10).min() / rest_volume)
        if (step + 1) % 30 == 0:
            velocities[(step + 1) // 30] = mean_velocity(simulation)
    assert smallest > 0.1
    assert centre_jacobians(simulation.positions, 10).min() / rest_volume > 0.5
    if scene in ("jelly-plane", "jelly-bowl"):
        assert np.abs(simulation.velocities).max() < 0.01   # at rest
    elif scene == "jelly-tilted":   # sliding at the Coulomb acceleration, as in the test above
        downhill = np.array([1.0, -1.0, 0.0]) / np.sqrt(2.0)
        acceleration = (velocities[10] - velocities[6]) @ downhill / 4.0
        assert acceleration == pytest.approx(9.8 * np.sqrt(0.5) * 0.7, rel=0.02)
    else:   # it slid off the sphere (it lands off-centre) and falls freely
        assert velocities[10] - velocities[9] == pytest.approx([0.0, -9.8, 0.0], abs=1e-4)


def test_scene_implicit_settings_reach_the_solver():
    """A scene's [implicit] table and Simulation keyword options give the very same step."""
    from springsim import load_scene

    overrides = ["implicit.newton_iterations=3", "implicit.cg_tolerance=1e-10",
                 "bodies.0.particles_per_edge=4"]
    from_scene = Simulation(load_scene("jelly-plane", overrides), integrator="implicit_euler",
                            dt=1 / 30)
    by_keyword = Simulation(load_scene("jelly-plane", overrides[2:]), integrator="implicit_euler",
                            dt=1 / 30, newton_iterations=3, cg_tolerance=1e-10)
    one_iteration = Simulation(load_scene("jelly-plane", overrides[2:]),
                               integrator="implicit_euler", dt=1 / 30)
    for simulation in (from_scene, by_keyword, one_iteration):
        simulation.advance(1.0)
    assert np.array_equal(from_scene.positions, by_keyword.positions)
    assert not np.array_equal(from_scene.positions, one_iteration.positions)


def test_the_first_guess_changes_the_solves_work_not_their_answer():
    """The first solve starts along the last step's velocity change (cg.mass_start). The solve's
    answer is the backward-Euler step whatever it starts from: stepping a swinging cloth with
    that guess and with none gives the same state to the CG tolerance, and the guess, a good
    one under the cloth's steady swing, takes fewer iterations."""
    scene = preset("cloth-hang")
    simulation = Simulation(scene, integrator="implicit_euler", dt=1.0 / 60.0, cg_tolerance=1e-10)
    simulation.step(20)
    guessed, unguessed = simulation.state.copy(), simulation.state.copy()
    unguessed.contacts.velocity_change[:] = 0.0
    assert np.abs(guessed.contacts.velocity_change).max() > 1e-3   # a real guess
    iterations = []
    for state in (guessed, unguessed):
        simulation.state = state
        simulation.integrator.statistics.cg_iterations[:] = 0
        simulation.step(1)
        iterations.append(int(simulation.integrator.statistics.cg_iterations[0]))
    scale = np.abs(unguessed.velocities).max()
    assert np.abs(guessed.velocities - unguessed.velocities).max() <= 1e-7 * scale
    assert np.abs(guessed.positions - unguessed.positions).max() <= 1e-7 * scale / 60.0
    assert iterations[0] < iterations[1]
