"""Oracles of body-body surface contact (issue 10, parts 5 and 9): stacking, a collapsing cloth
that never passes through itself, momentum conservation, Coulomb sliding on a tilted stack,
symmetry, independence of the body order, and bit-identical repeats whatever the threads.

Every oracle is physical or geometric (the bodies' keys are read from the scene, never from the
code under test); tests/crossings.py counts interpenetrations with its own plain NumPy.
implicit_euler's variants (dt 1/60) need the contacts inside its solve.
"""
import numpy as np
import pytest

from crossings import count_crossings
from springsim.bodies.cloth import Cloth
from springsim.bodies.cube import Cube
from springsim.integrators import available_threads, integrator_names
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.terrains import Plane

EXPLICIT = [name for name in integrator_names() if name != "implicit_euler"]
CHEAP = ["rk4", "symplectic_euler"]
G = 9.8


def body_slice(simulation, b):
    body = simulation.model.bodies[b]
    return slice(body.start, body.stop)


def all_surfaces(simulation):
    return np.concatenate([body.surface for body in simulation.model.bodies])


# -- two cubes stacked stay stacked ---------------------------------------------------------

def stacked_cubes(integrator, dt):
    """Two aligned 4^3 cubes (edge 1 m) on the plane y = -0.7, the upper one 0.2 m above the
    lower one's top."""
    lower = Cube(particles_per_edge=4, edge_length=1.0, position=(0.0, 0.0, 0.0))
    upper = Cube(particles_per_edge=4, edge_length=1.0, position=(0.0, 1.2, 0.0))
    scene = Scene(bodies=[lower, upper], terrains=[Plane(point=(0.0, -0.7, 0.0))],
                  integrator=integrator, dt=dt)
    return Simulation(scene), lower, upper


def check_stack_holds(integrator, dt, seconds=3.0):
    simulation, lower, upper = stacked_cubes(integrator, dt)
    low, high = body_slice(simulation, 0), body_slice(simulation, 1)
    every = max(1, round(0.01 / dt))
    worst = np.inf
    for _ in range(round(seconds / dt) // every):
        simulation.step(every)
        x = simulation.positions
        worst = min(worst, x[high, 1].min() - x[low, 1].max())
    # never below the lower cube's top, minus a thickness (the pair keeps the mean apart)
    assert worst >= -upper.thickness, worst
    # it rests on the lower cube: above the top and within reach of the contact, and still
    x = simulation.positions
    gap = x[high, 1].min() - x[low, 1].max()
    assert -upper.thickness <= gap <= 2 * 0.5 * (lower.thickness + upper.thickness), gap
    assert np.linalg.norm(simulation.velocities[high], axis=1).mean() < 0.05
    assert abs(x[high, 0].mean() - x[low, 0].mean()) < 0.05   # it did not slide off


@pytest.mark.parametrize("integrator", EXPLICIT)
def test_two_cubes_stacked_stay_stacked(integrator):
    check_stack_holds(integrator, 1e-3)


def test_two_cubes_stacked_stay_stacked_implicit_euler():
    check_stack_holds("implicit_euler", 1 / 60)


# -- a standing cloth collapsing on the floor never passes through itself --------------------

def standing_cloth(integrator, dt):
    """A 12 x 12 cloth (1 m, free) standing almost upright (89 degrees about x) just above the
    plane y = 0, thrown down at 3 m/s: it buckles and folds over itself on the floor."""
    cloth = Cloth(particles_per_edge=12, width=1.0, height=1.0, rotation_degrees=89.0,
                  pinned="none", position=(0.0, 0.53, 0.0), velocity=(0.0, -3.0, 0.0))
    scene = Scene(bodies=[cloth], terrains=[Plane(point=(0.0, 0.0, 0.0))],
                  integrator=integrator, dt=dt)
    return Simulation(scene), cloth


def stacked_share(x, spacing, thickness):
    """Share of the particles with another straight below them (closer than half a spacing
    horizontally, lower by more than half a thickness): a flat sheet has none."""
    across = np.hypot(x[:, None, 0] - x[None, :, 0], x[:, None, 2] - x[None, :, 2])
    above = (across < 0.5 * spacing) & (x[:, None, 1] - x[None, :, 1] > 0.5 * thickness)
    return np.any(above, axis=1).mean()


def check_collapse_never_crosses(integrator, dt, seconds=1.0, sample=0.004):
    simulation, cloth = standing_cloth(integrator, dt)
    triangles = all_surfaces(simulation)
    every = max(1, round(sample / dt))
    counts = []
    for _ in range(round(seconds / dt) // every):
        simulation.step(every)
        counts.append(count_crossings(simulation.positions, triangles))
    assert max(counts) == 0, [(i * every * dt, c) for i, c in enumerate(counts) if c]
    x = simulation.positions
    assert x[:, 1].max() < 0.4   # it came down: a 1 m sheet now lower than 0.4 m
    assert stacked_share(x, cloth.width / (cloth.particles_per_edge - 1),
                         cloth.contact_thickness()) > 0.2   # and folded over itself


@pytest.mark.parametrize("integrator", CHEAP)
def test_a_collapsing_cloth_never_crosses_itself(integrator):
    check_collapse_never_crosses(integrator, 2e-4)


def test_a_collapsing_cloth_never_crosses_itself_implicit_euler():
    check_collapse_never_crosses("implicit_euler", 1 / 60, seconds=1.5, sample=1 / 60)


# -- momentum is conserved in body-body contact ---------------------------------------------

# vbd conserves momentum only as far as its block descent converges: a sweep moves each
# particle against the others' latest positions, so a spring's two ends do not feel equal and
# opposite forces until the step's minimum is reached (measured at its default 10 iterations:
# 1.6e-11 to 3.9e-11 of the momentum scale, where the explicit methods keep 1e-12)
MOMENTUM_TOLERANCE = {"vbd": 1e-9}


@pytest.mark.parametrize("integrator", EXPLICIT)
def test_momentum_is_conserved_in_body_body_contact(integrator):
    """Two cubes of different masses, no gravity, no terrain, thrown at each other off-centre
    (friction acts too): the total momentum before and after is the same to round-off (vbd: to
    what its iterations leave, MOMENTUM_TOLERANCE)."""
    a = Cube(particles_per_edge=4, edge_length=1.0, position=(-0.8, 0.0, 0.0),
             velocity=(3.0, 0.5, 0.0), particle_mass=1.0)
    b = Cube(particles_per_edge=4, edge_length=1.0, position=(0.8, 0.3, 0.2),
             velocity=(-1.0, 0.0, 0.4), particle_mass=2.0, friction=0.6, static_friction=0.8,
             restitution=0.3)
    simulation = Simulation(Scene(bodies=[a, b], terrains=[], gravity=(0.0, 0.0, 0.0),
                                  integrator=integrator, dt=1e-3))
    masses = np.concatenate([np.full(4 ** 3, a.particle_mass), np.full(4 ** 3, b.particle_mass)])
    first = body_slice(simulation, 0)

    def momentum():
        return (masses[:, None] * simulation.velocities).sum(axis=0)

    before = momentum()
    scale = (masses * np.linalg.norm(simulation.velocities, axis=1)).sum()
    approach = simulation.velocities[first, 0].mean()
    simulation.advance(0.6)
    after = momentum()
    # they touched: the first cube's velocity along x changed by far more than round-off
    assert abs(simulation.velocities[first, 0].mean() - approach) > 0.5
    tolerance = MOMENTUM_TOLERANCE.get(integrator, 1e-12)
    assert np.all(np.abs(after - before) <= tolerance * scale), (after - before) / scale


# -- a cube sliding on a cube obeys g (sin - mu cos) ------------------------------------------

def tilted_stack(integrator, dt, theta, mu, drop=0.002):
    """A small 4^3 cube (edge 0.6 m) resting on a 5^3 cube (edge 2 m) held still (every
    particle pinned: a rigid slope; pinning only its bottom layer lets it shear under the
    sideways gravity, and the slope itself moves); gravity turned by ``theta`` so that the
    stack is tilted by it, the slope going down along +x; kinetic and static friction ``mu``
    on both bodies."""
    n = 5
    big = Cube(particles_per_edge=n, edge_length=2.0, position=(0.0, 0.0, 0.0),
               pinned=list(range(n ** 3)), friction=mu, static_friction=mu)
    small = Cube(particles_per_edge=4, edge_length=0.6, friction=mu, static_friction=mu,
                 position=(-0.5, 1.0 + 0.05 + 0.4 + drop, 0.1))   # ``drop`` above the contact
    scene = Scene(bodies=[big, small], terrains=[], integrator=integrator, dt=dt,
                  gravity=(G * np.sin(theta), -G * np.cos(theta), 0.0))
    return Simulation(scene)


@pytest.mark.parametrize("integrator, mu", [("rk4", 0.3), ("symplectic_euler", 0.3),
                                            ("rk4", 0.0), ("rk4", 0.5),
                                            ("implicit_euler", 0.3)])
def test_a_cube_slides_down_a_tilted_cube_at_g_sin_minus_mu_cos(integrator, mu):
    """Fit x(t) = x0 + v0 t + a t^2 / 2 to the small cube's centre of mass over 0.3 to 0.8 s
    (after the landing and the first rocking): a within 2% of g (sin theta - mu cos theta)
    for mu = 0 (no friction: the contact only holds the cube up), 0.3 and 0.5. The soft
    cube sways on its sliding bottom layer, which moves its centre of mass a little against
    the layer (0.1% measured for mu = 0.3). Under implicit_euler the friction is that of the
    solve's penalty contacts (collision/response/solve_friction.py), at the same dt."""
    theta, dt = np.radians(30.0), 1e-3
    simulation = tilted_stack(integrator, dt, theta, mu)
    small = body_slice(simulation, 1)
    times, centres = [], []
    for _ in range(80):
        simulation.step(round(0.01 / dt))
        times.append(simulation.time)
        centres.append(simulation.positions[small, 0].mean())
    times, centres = np.array(times), np.array(centres)
    window = (times > 0.3 - 1e-9) & (times < 0.8 + 1e-9)
    acceleration = 2 * np.polyfit(times[window], centres[window], 2)[0]
    expected = G * (np.sin(theta) - mu * np.cos(theta))
    assert acceleration == pytest.approx(expected, rel=0.02)
    # and it stays on top, a thickness above the slope (the top face is at y = 1 m)
    assert simulation.positions[small, 1].min() > 1.0


def test_a_cube_on_a_tilted_cube_sticks_when_static_friction_holds():
    """tan 30 degrees = 0.58 < mu = 0.8: put in contact (0.5 mm inside the pair's 5 cm), the
    small soft cube leans under the sideways gravity (its bottom layer shifts and partly lifts
    while it rocks, about 1 cm in the first 0.3 s), then stands: from 0.4 to 0.8 s its bottom
    layer, which touches the slope, moves less than 1 mm, against the 1.2 m a frictionless cube
    slides in that time, and it is still at the end."""
    theta, dt = np.radians(30.0), 1e-3
    simulation = tilted_stack("rk4", dt, theta, 0.8, drop=-0.0005)
    small = simulation.model.bodies[1]
    bottom = np.arange(4 ** 3).reshape(4, 4, 4)[:, 0, :].ravel() + small.start
    simulation.advance(0.4)
    start = simulation.positions[bottom, 0].mean()
    simulation.advance(0.4)
    slip = simulation.positions[bottom, 0].mean() - start
    assert abs(slip) < 0.001, slip
    assert abs(simulation.velocities[bottom, 0].mean()) < 0.002


# -- a symmetric scene stays symmetric -------------------------------------------------------

def mirror_scene(integrator, bodies_first_cloth=True):
    """A 4^3 cube dropped centred on a 11 x 11 cloth pinned at its corners. The mirror
    x <-> z maps the scene onto itself, meshes included (the cells' diagonals run along
    (+1, +1) in both the cloth's (x, z) and every cube face's grid)."""
    cloth = Cloth(particles_per_edge=11, width=1.5, height=1.5, position=(0.0, 0.0, 0.0))
    # lattice offsets (-2 .. 1) x 0.2 m: centred over (0, 0) with its bottom 0.15 m up
    cube = Cube(particles_per_edge=4, edge_length=0.6, position=(0.1, 0.55, 0.1))
    bodies = [cloth, cube] if bodies_first_cloth else [cube, cloth]
    return Scene(bodies=bodies, terrains=[], integrator=integrator, dt=2e-4)


def mirror_map(simulation):
    """Each particle's mirror image under x <-> z, for the scene of mirror_scene."""
    image = np.empty(simulation.model.particle_count, np.int64)
    for body, built in zip(simulation.scene.bodies, simulation.model.bodies):
        if isinstance(body, Cloth):
            n = body.particles_per_edge
            grid = np.arange(n * n).reshape(n, n)           # (row: z, column: x)
            image[built.start:built.stop] = grid.T.ravel() + built.start
        else:
            n = body.particles_per_edge
            lattice = np.arange(n ** 3).reshape(n, n, n)     # (x, y, z)
            image[built.start:built.stop] = lattice.transpose(2, 1, 0).ravel() + built.start
    return image


@pytest.mark.parametrize("integrator", CHEAP)
def test_a_symmetric_drop_stays_symmetric(integrator):
    simulation = Simulation(mirror_scene(integrator))
    image = mirror_map(simulation)
    x = simulation.positions
    assert np.abs(x[image][:, [2, 1, 0]] - x).max() < 1e-12   # the start is symmetric
    cube = body_slice(simulation, 1)
    cloth = body_slice(simulation, 0)
    simulation.advance(1.0)
    x = simulation.positions
    # it landed on the cloth (the cube is held above the cloth's lowest point)
    assert x[cube, 1].min() > x[cloth, 1].min()
    assert x[cube, 1].mean() < 0.45 - 0.1
    assert np.abs(x[image][:, [2, 1, 0]] - x).max() < 1e-9


# -- the body order changes nothing beyond round-off ------------------------------------------

@pytest.mark.parametrize("integrator", CHEAP)
def test_renumbered_bodies_give_the_same_trajectory(integrator):
    one = Simulation(mirror_scene(integrator, bodies_first_cloth=True))
    other = Simulation(mirror_scene(integrator, bodies_first_cloth=False))
    # particle p of ``one`` is particle order[p] of ``other``
    order = np.concatenate([np.arange(b.start, b.stop) for b in reversed(other.model.bodies)])
    assert np.array_equal(one.positions, other.positions[order])
    worst = 0.0
    for _ in range(10):
        one.advance(0.08)
        other.advance(0.08)
        worst = max(worst, np.abs(one.positions - other.positions[order]).max())
    cube = body_slice(one, 1)
    assert one.positions[cube, 1].mean() < 0.45 - 0.1   # the cube fell onto the cloth
    assert worst < 1e-9


# -- the same input gives bit-identical output --------------------------------------------------

def contact_rich(integrator="rk4", threads=None):
    """Two cubes dropped on a free cloth lying on the plane, off-centre and turned."""
    cloth = Cloth(particles_per_edge=12, width=1.5, height=1.5, pinned="none",
                  position=(0.0, 0.02, 0.0))
    a = Cube(particles_per_edge=4, edge_length=0.5, position=(-0.2, 0.5, 0.1),
             rotation_degrees=20.0)
    b = Cube(particles_per_edge=4, edge_length=0.5, position=(0.25, 0.9, -0.15),
             rotation_degrees=-35.0, rotation_axis=(0.0, 1.0, 1.0))
    scene = Scene(bodies=[cloth, a, b], terrains=[Plane(point=(0.0, 0.0, 0.0))],
                  integrator=integrator, dt=2e-4)
    return Simulation(scene, threads=threads)


def test_the_same_scene_twice_is_bit_identical():
    first, second = contact_rich(), contact_rich()
    first.advance(0.6)
    second.advance(0.6)
    assert np.array_equal(first.positions, second.positions)
    assert np.array_equal(first.velocities, second.velocities)


def test_contact_is_bit_identical_for_one_and_two_threads():
    counts = sorted({1, min(2, available_threads())})
    runs = [contact_rich(threads=count) for count in counts]
    for run in runs:
        run.advance(0.6)
    for run in runs[1:]:
        assert np.array_equal(run.positions, runs[0].positions)
        assert np.array_equal(run.velocities, runs[0].velocities)


@pytest.mark.parametrize("integrator", ["rk4", "implicit_euler"])
def test_one_step_a_call_is_bit_identical_to_one_call_and_keeps_the_pair_list(integrator):
    """The pair list lives on between calls (in the state: State.pairs), so stepping one step a
    call searches no more than one call does; the list decides nothing, so the trajectory is
    the same to the bit. Then a state far from the list's (the start again) is searched
    afresh, and again gives the same trajectory."""
    dt = 2e-4 if integrator == "rk4" else 1 / 60
    steps = 300 if integrator == "rk4" else 30
    whole, single = contact_rich(integrator), contact_rich(integrator)
    whole.dt = single.dt = dt
    start = single.state.copy()
    whole.step(steps)
    searches, found_at = 0, single.state.pairs.found_at.copy()
    for _ in range(steps):
        single.step(1)
        searches += not np.array_equal(single.state.pairs.found_at, found_at, equal_nan=True)
        found_at = single.state.pairs.found_at.copy()
    assert np.array_equal(single.positions, whole.positions)
    assert np.array_equal(single.velocities, whole.velocities)
    if integrator == "rk4":   # the list was kept between most calls
        # (counted by what it was found at: the array's id, counted before, was reused by
        # the allocator; backward Euler's steps of 1/60 s carry the falling cubes out of the
        # list's reach at nearly every step, one call or many)
        assert searches < steps / 10
    kept = single.state.pairs
    single.state = start
    single.step(steps)
    assert single.state.pairs.found_at is not kept.found_at   # searched again
    assert np.array_equal(single.positions, whole.positions)


# -- a flat cloth of any resolution lists no pair of its own --------------------------------

@pytest.mark.parametrize("particles_per_edge", [10, 25, 60, 100])
def test_a_flat_default_cloth_lists_no_pair_of_its_own(particles_per_edge):
    """With its default thickness, a flat self-colliding cloth of any resolution (4 m wide:
    spacing 0.44 to 0.04 m) has no point within its thickness plus the search's skin of a
    triangle it does not share an edge with, measured with plain NumPy over every (point,
    triangle) pair; and the pair search lists none, so a cloth where nothing touches costs no
    narrow phase. The thickness is below half the spacing, as self-collision requires."""
    from springsim.collision.broad_phase.surfaces import surface_pairs
    from springsim.collision.pair_lists.keeping import start_surface_pairs, surface_skin
    cloth = Cloth(particles_per_edge=particles_per_edge)
    simulation = Simulation(Scene(bodies=[cloth], terrains=[], dt=1e-3))
    arrays, x = simulation.model.arrays, simulation.positions
    spacing = 4.0 / (particles_per_edge - 1)
    thickness = arrays.body_thickness[0]
    assert 0 < thickness < 0.5 * spacing
    triangles = all_surfaces(simulation)
    corners = x[triangles]                                   # (T, 3, 3)
    # in the flat sheet, a point's distance to a triangle is its distance in the plane; the
    # nearest triangle without the point or a neighbour as a corner is at least a spacing off
    sharing = {tuple(sorted(edge)) for t in triangles for edge in ((t[0], t[1]), (t[1], t[2]),
                                                                   (t[0], t[2]))}
    neighbours = {p: set() for p in range(len(x))}
    for a, b in sharing:
        neighbours[a].add(b)
        neighbours[b].add(a)
    reach = thickness + surface_skin(arrays)
    if particles_per_edge <= 25:   # every pair, with NumPy's distances to the corners' box
        low, high = corners.min(axis=1), corners.max(axis=1)
        for p in range(len(x)):
            gap = np.linalg.norm(np.maximum(0, np.maximum(low - x[p], x[p] - high)), axis=1)
            near = np.nonzero(gap < reach)[0]
            for t in near:
                assert p in triangles[t] or neighbours[p] & set(triangles[t]), (p, t)
    skin = surface_skin(arrays)
    points, edges = surface_pairs(arrays, x, skin, skin)   # the search itself, not the proof
    assert len(points) == 0 and len(edges) == 0
    assert len(start_surface_pairs(arrays, x)[0]) == 0   # nor what the contact pass starts with
