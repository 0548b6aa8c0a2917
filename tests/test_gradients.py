"""Gradients through the simulation (springsim.gradients) against central finite differences of
the forward run itself: each parameter kind under each integrator with an adjoint, on a 3 x 3 x 3
cube with one pinned corner (so that its springs stretch) and a few steps."""
import numpy as np
import pytest

from springsim.bodies.cube import Cube
from springsim.errors import SceneError
from springsim.gradients import gradient, prepare, run_gradient
from springsim.gradients.losses import as_loss
from springsim.scene import Scene

STEPS = {"symplectic_euler": 0.002, "rk4": 0.002, "implicit_euler": 0.01}
TIGHT = {"implicit_euler": {"cg_tolerance": 1e-13, "cg_max_iterations": 2000}}


def small_scene():
    return Scene(bodies=[Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, 2.0, 0.0),
                              velocity=(0.3, 0.1, -0.2), pinned=(0,))], terrains=[], drag=0.1)


def weighted_squares(positions):
    weights = np.linspace(1.0, 2.0, positions.size).reshape(positions.shape)
    return float(np.sum(weights * positions ** 2)), 2.0 * weights * positions


def jittered(scene):
    """Initial positions off the rest shape: at rest every spring sits at L = r, where
    implicit_euler's matrix drops the compressive stiffness (implicit/jacobian.py), a kink that
    a particle's own move crosses (its derivative is one-sided there)."""
    from springsim.model import build_model
    model = build_model(scene)
    offsets = np.random.default_rng(1).normal(0.0, 0.01, model.initial_positions.shape)
    return model.initial_positions + offsets


def loss_at(scene, integrator, wrt=(), values=None, start=None):
    dt = STEPS[integrator]
    values = dict(values or {})
    if start is not None:
        values.setdefault("initial_positions", start)
        wrt = list(dict.fromkeys(list(wrt) + ["initial_positions"]))
    _, simulation, _ = prepare(scene, list(wrt) or ["drag"], values, integrator=integrator,
                               dt=dt, **TIGHT.get(integrator, {}))
    loss = as_loss(weighted_squares, 1 / (4 * dt))
    return run_gradient(simulation, loss, 10 * dt).loss


def central_difference(scene, integrator, name, base, component, step, start=None):
    values = []
    for sign in (1.0, -1.0):
        value = np.array(base, float)
        value.ravel()[component] += sign * step
        values.append(loss_at(scene, integrator, [name], {name: value}, start))
    return (values[0] - values[1]) / (2 * step)


SCENE_KEYS = ["bodies.0.structural.ks", "bodies.0.shear.kd", "bodies.0.bend.ks", "gravity",
              "drag", "bodies.0.particle_mass", "bodies.0.velocity", "bodies.0.position"]


def assert_gradients_match(scene_of, integrator, names):
    """The gradient of every component of every parameter ``names`` names, over 10 steps of
    the scene ``scene_of()`` makes, against central differences of the forward run."""
    from springsim.gradients.parameters import parameter
    dt = STEPS[integrator]
    _, grads = gradient(scene_of(), weighted_squares, names, duration=10 * dt,
                        integrator=integrator, dt=dt, fps=1 / (4 * dt),
                        **TIGHT.get(integrator, {}))
    for name in names:
        base = parameter(scene_of(), name).value
        for j in range(base.size):
            step = 1e-5 * max(abs(base.ravel()[j]), 1.0)
            expected = central_difference(scene_of(), integrator, name, base, j, step)
            got = np.ravel(grads[name])[j]
            assert got == pytest.approx(expected, rel=1e-5, abs=1e-7), (name, j)


@pytest.mark.parametrize("integrator", list(STEPS))
def test_scene_keys_match_finite_differences(integrator):
    assert_gradients_match(small_scene, integrator, SCENE_KEYS)


@pytest.mark.parametrize("integrator", list(STEPS))
def test_model_arrays_match_finite_differences(integrator):
    """Per-particle and per-spring arrays: a few components each, by finite differences (the
    absolute floor is rounding: the loss is about 50, its differences over 1e-6)."""
    scene = small_scene()
    dt = STEPS[integrator]
    names = ["initial_positions", "initial_velocities", "masses", "rest_lengths",
             "bodies.0.stiffness_field", "spring_kd"]
    start = jittered(scene)
    _, simulation, params = prepare(scene, names, {"initial_positions": start},
                                    integrator=integrator, dt=dt, **TIGHT.get(integrator, {}))
    model = simulation.model
    result = run_gradient(simulation, as_loss(weighted_squares, 1 / (4 * dt)), 10 * dt)
    for p in params:
        grad = np.ravel(p.gradient(scene, model, result))
        base = p.read(model)
        for j in (1, 5, grad.size - 1):
            step = 1e-6 * max(abs(base.ravel()[j]), 1.0)
            expected = central_difference(scene, integrator, p.name, base, j, step, start)
            assert grad[j] == pytest.approx(expected, rel=1e-5, abs=1e-7), (p.name, j)


def test_newton_iterations_and_determinism():
    """Three Newton iterations (two solved again by the adjoint); the same bits whatever the
    thread count."""
    scene = small_scene()
    options = {"integrator": "implicit_euler", "dt": 0.01, "duration": 0.05, "fps": 50,
                   "newton_iterations": 3, "cg_tolerance": 1e-13}
    one = gradient(scene, weighted_squares, ["bodies.0.structural.ks"], threads=1, **options)
    two = gradient(scene, weighted_squares, ["bodies.0.structural.ks"], threads=2, **options)
    assert one[1]["bodies.0.structural.ks"] == two[1]["bodies.0.structural.ks"]
    base = 2000.0
    values = []
    for sign in (1, -1):
        changed = Scene(**scene.__dict__)
        changed.bodies = [Cube(**scene.bodies[0].__dict__)]
        changed.bodies[0].structural = type(scene.bodies[0].structural)(base + sign * 0.02, 60.0)
        values.append(gradient(changed, weighted_squares, ["drag"], threads=1, **options)[0])
    assert one[1]["bodies.0.structural.ks"] == pytest.approx((values[0] - values[1]) / 0.04,
                                                             rel=1e-5)


def test_checkpoints_give_the_same_gradient():
    scene = small_scene()
    names = ["bodies.0.structural.ks", "initial_velocities"]
    _, simulation, _ = prepare(scene, names, integrator="rk4", dt=0.002)
    loss = as_loss(weighted_squares, 100)
    kept = run_gradient(simulation, loss, 0.04)
    _, simulation, _params = prepare(scene, names, integrator="rk4", dt=0.002)
    # room for 8 of the 27 particles' steps, each (x, v) and rk4's four stages' accelerations
    strided = run_gradient(simulation, loss, 0.04, memory_limit=8 * 27 * (6 + 12) * 8)
    assert strided.stored_bytes < kept.stored_bytes
    np.testing.assert_array_equal(kept.v0_bar, strided.v0_bar)
    np.testing.assert_array_equal(kept.bar.ks, strided.bar.ks)


@pytest.mark.parametrize("wrt, message", [
    (["bodies.0.nothing"], "names no parameter"),
    (["bodies.0.particles_per_edge"], "cannot be differentiated"),
    (["bodies.3.stiffness_field"], "names no body"),
])
def test_bad_parameters_are_one_line(wrt, message):
    with pytest.raises(SceneError, match=message):
        gradient(small_scene(), weighted_squares, wrt, duration=0.01, integrator="rk4", dt=0.002)


def test_nan_loss_and_untouched_terrain():
    with pytest.raises(SceneError, match="finite"):
        gradient(small_scene(), lambda x: (float("nan"), 0 * x), ["drag"], duration=0.01,
                 integrator="rk4", dt=0.002)
    from springsim.terrains.plane import Plane
    scene = small_scene()
    scene.bodies[0].pinned = ()
    scene.terrains = [Plane(point=(0.0, 0.0, 0.0))]   # 1.5 m below: not reached in 0.1 s
    _, grads = gradient(scene, weighted_squares, ["drag"], duration=0.1, integrator="rk4",
                            dt=0.002)
    assert np.isfinite(grads["drag"])



# --- terrain contact ----------------------------------------------------------------------------

SLOPE = 0.1   # the plane's rise per metre: the cube slides where friction < SLOPE
CONTACT_CASES = {   # (friction, the cube's height, its velocity)
    "lands and slides": (0.05, 0.53, (0.3, -1.5, 0.0)),   # lands at 1.5 m/s: bounces (e = 0.5)
    "rests": (0.3, 0.504, (0.0, -0.01, 0.0)),             # held by static friction
}
CONTACT_KEYS = ["bodies.0.structural.ks", "terrains.0.friction", "terrains.0.restitution",
                "bodies.0.velocity"]


def tilted_scene(case):
    """A 3 x 3 x 3 cube turned to lie flat on a plane tilted by SLOPE, its bottom face in the
    contact band or just above it."""
    from springsim.terrains.plane import Plane
    friction, height, velocity = CONTACT_CASES[case]
    cube = Cube(particles_per_edge=3, edge_length=1.0, position=(0.0, height, 0.0),
                velocity=velocity, rotation_degrees=-float(np.degrees(np.arctan(SLOPE))),
                rotation_axis=(0.0, 0.0, 1.0))
    return Scene(bodies=[cube], terrains=[Plane(point=(0.0, 0.0, 0.0), normal=(SLOPE, 1.0, 0.0),
                                                friction=friction, restitution=0.5)], drag=0.1)


def forward_loss(scene, integrator, steps, name, value):
    """The loss of the forward run alone, with parameter ``name`` set to ``value``."""
    from springsim.gradients.tape import record
    dt = STEPS[integrator]
    scene, simulation, _ = prepare(scene, [name], {name: value}, integrator=integrator, dt=dt,
                                   **TIGHT.get(integrator, {}))
    loss = as_loss(weighted_squares, 1 / (4 * dt))
    frame_steps = loss.frame_steps(steps * dt, dt, simulation.model.particle_count)
    frames, _ = record(simulation, steps, frame_steps, 1 << 30)
    return loss(frames)[0]


@pytest.mark.parametrize("case", list(CONTACT_CASES))
@pytest.mark.parametrize("integrator", list(STEPS))
def test_terrain_contact_matches_finite_differences(integrator, case):
    """Resting, landing (a bounce with restitution) and sliding on a tilted plane: the motion
    is smooth in these parameters (no particle changes branch within the differences)."""
    from springsim.gradients.parameters import parameter
    scene = tilted_scene(case)
    dt, steps = STEPS[integrator], 15
    _, grads = gradient(scene, weighted_squares, CONTACT_KEYS, duration=steps * dt,
                        integrator=integrator, dt=dt, fps=1 / (4 * dt),
                        **TIGHT.get(integrator, {}))
    for name in CONTACT_KEYS:
        base = parameter(scene, name).value
        for j in range(base.size):
            step = 1e-5 * max(abs(base.ravel()[j]), 1.0)
            values = []
            for sign in (1.0, -1.0):
                value = np.array(base, float)
                value.ravel()[j] += sign * step
                values.append(forward_loss(scene, integrator, steps, name, value))
            expected = (values[0] - values[1]) / (2 * step)
            assert np.ravel(grads[name])[j] == pytest.approx(expected, rel=1e-5, abs=1e-7), \
                (name, j)


def test_fit_command_recovers_stiffness(tmp_path, capsys):
    """`springsim fit` on a take of the small cube with soft structural springs (ks = 200, so
    that 0.3 s of swinging depends on them), started at 400."""
    import json

    from springsim.cli import main
    from springsim.scenefile import scene_to_toml

    scene_file = tmp_path / "cube.toml"
    scene = small_scene()
    scene.bodies[0].structural = type(scene.bodies[0].structural)(200.0, 60.0)
    scene_file.write_text(scene_to_toml(scene))
    options = ["--integrator", "rk4", "--dt", "0.002"]
    take = tmp_path / "take.npz"
    assert main(["run", str(scene_file), *options, "--duration", "0.3", "--fps", "100",
                 "--out", str(take), "--quiet"]) == 0
    out = tmp_path / "fitted.toml"
    assert main(["fit", str(scene_file), *options, "--observed", str(take), "--fit",
                 "bodies.0.structural.ks", "--set", "bodies.0.structural.ks=400",
                 "--out", str(out)]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert lines[0].startswith("iteration 1: loss")
    answer = json.loads(lines[-1])
    assert answer["fitted"]["bodies.0.structural.ks"] == pytest.approx(200.0, rel=1e-2)
    assert "ks = " in out.read_text()


def test_fit_keeps_friction_in_its_range():
    """A take of the cube sliding down the tilted plane without friction, fitted from friction
    0.1: the loss falls toward 0 and beyond it (where no scene runs), so the fit must stop at
    the range's end, 0, instead of stepping below it."""
    import springsim
    from springsim.gradients.fit import fit
    from springsim.gradients.losses import ObservedTake

    def sliding(friction):
        scene = tilted_scene("lands and slides")
        scene.terrains[0].friction = friction
        return scene

    simulation = springsim.Simulation(sliding(0.0), integrator="rk4", dt=0.002)
    times, frames = [0.0], [simulation.positions.copy()]
    for _ in range(10):
        simulation.step(5)
        times.append(simulation.time)
        frames.append(simulation.positions.copy())
    observed = ObservedTake({"time": np.array(times), "positions": np.array(frames)})
    result = fit(sliding(0.1), observed, ["terrains.0.friction"], 0.1, integrator="rk4",
                 dt=0.002)
    assert 0.0 <= result.values["terrains.0.friction"] < 1e-3


@pytest.mark.parametrize("scene_of", [small_scene, lambda: tilted_scene("lands and slides")],
                         ids=["free", "contact"])
def test_implicit_gradient_is_of_what_was_computed(scene_of):
    """The adjoint treats the forward's CG solves as exact: the gradient at cg_tolerance tol
    differs from that of the same run solved tightly by the tolerance's order (measured: 0.5
    to 4 times tol)."""
    scene = scene_of()
    keys = ["bodies.0.structural.ks", "gravity", "bodies.0.velocity"]
    options = {"integrator": "implicit_euler", "dt": 0.01, "duration": 0.1, "fps": 50,
               "cg_max_iterations": 5000}
    tight = gradient(scene, weighted_squares, keys, cg_tolerance=1e-13, **options)[1]
    for tolerance in (1e-5, 1e-7):
        loose = gradient(scene, weighted_squares, keys, cg_tolerance=tolerance, **options)[1]
        for name in keys:
            error = np.max(np.abs(np.ravel(loose[name]) - np.ravel(tight[name])))
            assert error <= 10 * tolerance * np.max(np.abs(tight[name])), (name, tolerance)


def test_kernels_match_their_numpy_references():
    """gradients/kernels.py against physics.py's NumPy forces and VJPs, on random springs: some
    stretched, some compressed (the clamped stiffness), one of zero length."""
    from springsim.gradients import physics
    from springsim.gradients.contact import Planes
    rng = np.random.default_rng(3)
    count, springs = 12, 30
    pairs = np.array([rng.choice(count, 2, replace=False) for _ in range(springs)])
    x, v, u, g = (rng.normal(size=(count, 3)) for _ in range(4))
    x[pairs[0, 1]] = x[pairs[0, 0]]   # a spring of zero length
    free = np.ones(count, bool)
    free[0] = False
    physical = physics.Physical(rng.uniform(1, 3, springs), rng.uniform(0.1, 1, springs),
                                rng.uniform(0.5, 2, springs), rng.uniform(1, 2, count),
                                rng.uniform(0, 1, count), np.array([0.0, -9.8, 0.0]), free,
                                pairs[:, 0].copy(), pairs[:, 1].copy(), np.empty(0),
                                np.empty(0), Planes(*(np.empty(0),) * 3),
                                np.zeros(6), np.zeros((1, 4)), np.zeros((0, 8)),
                                np.zeros((0, 3), np.int64), np.zeros(0), np.zeros(2),
                                np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)),
                                np.zeros(0), np.zeros(0), np.zeros((0, 1)), np.zeros((0, 1)),
                                np.zeros((0, 4), np.int64), np.zeros((0, 4)), np.zeros(0),
                                np.zeros(0))
    h = 0.01
    calls = [
        lambda f, xb, ub, bar: f["spring_forces_vjp"](physical, x, v, g, xb, ub, bar),
        lambda f, xb, ub, bar: f["stiffness_product_vjp"](physical, x, u, g, xb, ub, bar),
        lambda f, xb, ub, bar: f["system_product_vjp"](physical, x, u, g, h, xb, bar),
    ]
    fast = {name: getattr(physics, name) for name in
            ("spring_forces_vjp", "stiffness_product_vjp", "system_product_vjp")}
    slow = {name: getattr(physics, "reference_" + name) for name in fast}
    for call in calls:
        results = []
        for functions in (fast, slow):
            bar = physics.Cotangents.zeros(physical)
            xb, ub = np.zeros((count, 3)), np.zeros((count, 3))
            call(functions, xb, ub, bar)
            results.append((xb, ub, bar.ks, bar.kd, bar.rest, bar.mass, bar.drag))
        for got, expected in zip(*results):
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(physics.stiffness_product(physical, x, u),
                               physics.reference_stiffness_product(physical, x, u),
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(physics.spring_forces(physical, x, v),
                               physics.reference_spring_forces(physical, x, v),
                               rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("name, value", [("bodies.0.stiffness_regions.x=0.1", [1.3, 0.7]),
                                         ("bodies.0.stiffness_field", None)])
def test_stiffness_scales_away_from_one(name, value):
    """A stiffness scale's gradient at a scale other than 1 (fit moves it there): two regions
    cut at x = 0.1, and a random per-spring field."""
    scene = small_scene()
    _, simulation, (p,) = prepare(scene, [name], None, integrator="rk4", dt=0.002)
    if value is None:
        value = np.random.default_rng(2).uniform(0.5, 2.0, p.read(simulation.model).shape)
    value = np.asarray(value, float)
    _, simulation, (p,) = prepare(scene, [name], {name: value}, integrator="rk4", dt=0.002)
    result = run_gradient(simulation, as_loss(weighted_squares, 125), 0.02)
    grad = np.ravel(p.gradient(scene, simulation.model, result))
    for j in (0, value.size - 1):
        step = 1e-6
        expected = central_difference(scene, "rk4", name, value, j, step)
        assert grad[j] == pytest.approx(expected, rel=1e-5, abs=1e-7), j


def test_the_rk4_step_adjoint_in_runs_matches_numpy(monkeypatch):
    """run_kernels.rk4_step_vjp (springs in runs, SIMD loops) against the same step's adjoint in
    NumPy (RK4Adjoint.update_vjp through physics.py), on two cubes whose springs fill runs with
    holes and (with runs of fewer than 100 springs refused) leave some loose, each spring with
    its own stiffness (a field)."""
    import springsim
    from springsim.gradients.adjoints import ExplicitAdjoint, RK4Adjoint
    from springsim.gradients.physics import Cotangents, Physical
    from springsim.spring_runs import run_layout

    monkeypatch.setattr("springsim.spring_runs.MIN_RUN", 100)
    scene = Scene(bodies=[Cube(particles_per_edge=6, edge_length=1.0, position=(0.0, 2.0, 0.0)),
                          Cube(particles_per_edge=3, edge_length=0.5, position=(2.0, 2.0, 0.0))],
                  terrains=[], integrator="rk4", dt=1e-3)
    sim = springsim.Simulation(scene)
    rng = np.random.default_rng(11)
    physical = Physical.of(sim.model)
    physical = physical._replace(ks=physical.ks * rng.uniform(0.5, 2.0, len(physical.ks)))
    layout = run_layout(physical.a, physical.b)
    assert len(layout.loose) > 0 and (layout.entry_spring < 0).any()
    x = sim.positions + 0.02 * rng.standard_normal(sim.positions.shape)
    v = rng.standard_normal(x.shape)
    x_bar, v_bar = rng.standard_normal(x.shape), rng.standard_normal(x.shape)
    adjoint = RK4Adjoint(sim.integrator, sim.model)
    # the stages' accelerations as the forward's step keeps them (tape.py), for the kernel to
    # take instead of evaluating its own: at the scene's own stiffness, which the forward has
    sim.state.positions[:], sim.state.velocities[:] = x, v
    kept, starts = np.empty((1, sim.keeps_stages(), len(x), 3)), np.empty((1, 2, len(x), 3))
    sim.step_keeping(kept, starts)
    kept = kept[0]
    cases = ((physical, RK4Adjoint.step_vjp, None), (physical, ExplicitAdjoint.step_vjp, None),
             (Physical.of(sim.model), RK4Adjoint.step_vjp, kept),
             (Physical.of(sim.model), ExplicitAdjoint.step_vjp, None))
    results = []
    for parameters, step_vjp, stages in cases:
        bar = Cotangents.zeros(parameters)
        got = step_vjp(adjoint, parameters, 1e-3, (x, v), (x, v), x_bar, v_bar, bar, stages)
        results.append((*got, bar.ks, bar.kd, bar.rest, bar.mass, bar.drag, bar.gravity))
    for fast, numpy_reference in [*zip(*results[:2]), *zip(*results[2:])]:
        scale = np.max(np.abs(numpy_reference))
        np.testing.assert_allclose(fast, numpy_reference, rtol=0, atol=1e-12 * scale)


def test_a_run_keeping_its_stages_is_the_same_run():
    """Simulation.step_keeping (the gradient's tape under rk4) takes the same steps, bit for bit,
    as step(1) a call, through a cube's landing on a tilted plane and resting there, and keeps
    each step's start; what it keeps of the stages are their accelerations, whose RK4
    combination is the step's change in velocity (off contact)."""
    import springsim

    scene = springsim.load_scene("jelly-tilted", ["bodies.0.particles_per_edge=4",
                                                  "bodies.0.position=[2, 3.5, 0]"])
    plain = springsim.Simulation(scene, integrator="rk4", dt=2e-3)
    keeping = springsim.Simulation(scene, integrator="rk4", dt=2e-3)
    assert keeping.keeps_stages() == 4
    steps, particles = 200, plain.model.particle_count
    kept, starts = np.empty((steps, 4, particles, 3)), np.empty((steps, 2, particles, 3))
    keeping.step_keeping(kept, starts)
    for n in range(steps):
        np.testing.assert_array_equal(starts[n, 0], plain.positions)
        np.testing.assert_array_equal(starts[n, 1], plain.velocities)
        plain.step(1)
    np.testing.assert_array_equal(keeping.positions, plain.positions)
    np.testing.assert_array_equal(keeping.velocities, plain.velocities)
    change = 2e-3 / 6 * (kept[0, 0] + 2 * kept[0, 1] + 2 * kept[0, 2] + kept[0, 3])
    np.testing.assert_allclose(starts[1, 1] - starts[0, 1], change, rtol=0, atol=1e-12)
    # one call's clock: its start plus n h (step by step, the sum rounds otherwise)
    assert keeping.time == steps * 2e-3 and keeping.steps_taken == plain.steps_taken == steps
    x = keeping.positions
    assert np.min(x[:, 0] + x[:, 1]) / np.sqrt(2.0) < 0.011   # on the plane, within its band


def test_the_far_test_bounds_what_it_stands_for():
    """contact.reach (RK4's adjoint asks it at every step whether a step may skip contact): a
    plane's compiled least distance is the least distance of a free particle (pinned ones left
    out), a sphere's the same through its own distance, and the speed a bound on the fastest
    particle's, at most sqrt(3) times it."""
    from springsim.gradients.contact import reach
    from springsim.terrains.plane import Flat
    from springsim.terrains.sphere import Round

    rng = np.random.default_rng(5)
    x, v = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    offset = rng.uniform(0.0, 0.1, 50)
    free = np.ones(50, bool)
    free[np.argmin(x[:, 1])] = False   # the lowest particle is pinned: it does not count
    plane = Flat(np.array([0.1, -0.2, 0.3]), np.array([0.6, 0.8, 0.0]))
    sphere = Round(np.array([0.0, -3.0, 0.0]), 1.0, 1.0)
    planes = type("Planes", (), {"offset": offset})()
    physical = type("Physical", (), {"free": free, "planes": planes})()
    found = reach(physical, [(0, plane), (1, sphere)], x, v)
    for j, shape in enumerate((plane, sphere)):
        assert found.nearest[j] == pytest.approx(shape.distance(x, offset)[free].min(),
                                                 rel=1e-12)
    fastest = np.linalg.norm(v, axis=1).max()
    assert fastest <= found.speed <= np.sqrt(3.0) * fastest


def test_the_far_test_of_a_whole_run_is_each_steps():
    """contact.far_steps (every step of a kept run at once, as RK4's adjoint looks over a
    stretch) says what far_from_terrains says step by step, over a run in which the default
    cube falls onto the plane: far steps, then near ones."""
    import springsim
    from springsim.gradients.contact import far_from_terrains, far_steps
    from springsim.gradients.physics import Physical
    from springsim.gradients.tape import keeping_run

    simulation = springsim.Simulation(springsim.load_scene("jelly-plane"), integrator="rk4",
                                      dt=1e-3)
    simulation.advance(1.0)   # falling: the far test lets go 0.255 s later
    run = keeping_run(simulation, 300, 4)
    physical = Physical.of(simulation.model)
    h = simulation.dt
    each = np.array([far_from_terrains(physical, h, run.starts[k], run.starts[k + 1])[0]
                     for k in range(len(run.kept))])
    assert each.any() and not each.all()
    assert np.array_equal(far_steps(physical, h, run.starts), each)
