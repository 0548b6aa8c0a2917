"""Gradients through the wind (gradients/wind.py) against central finite differences of the
forward run: the wind's velocity, keys and settings, and the model's parameters with the wind
blowing, under each integrator with an adjoint, on a cube, a cloth, a cube sliding on a
tilted plane and balls beside a cloth (each ball a sphere in the air)."""
import numpy as np
import pytest

from springsim.bodies.balls import Ball, Balls
from springsim.bodies.cloth import Cloth
from springsim.scene import Scene
from springsim.springs import SpringParameters
from springsim.wind import Gusts, Wind, WindKey
from test_gradients import STEPS, assert_gradients_match, small_scene, tilted_scene

WIND_KEYS = ["wind.velocity", "wind.density", "wind.drag", "wind.friction",
             "wind.gusts.strength", "wind.gusts.length", "bodies.0.structural.ks",
             "bodies.0.velocity"]


def gusty(scene):
    scene.wind = Wind(velocity=(8.0, 1.0, -3.0), density=1.2, drag=1.2, friction=0.05,
                      gusts=Gusts(strength=0.4, length=0.7, seed=3))
    return scene


def flag():
    """A light 4 x 4 cloth pinned along one edge, broadside to a gusty wind (springs soft
    enough for the explicit methods' step)."""
    springs = SpringParameters(ks=2000.0, kd=5.0)
    cloth = Cloth(particles_per_edge=4, width=1.0, height=1.0, position=(0.0, 2.0, 0.0),
                  particle_mass=0.2, structural=springs, shear=springs, bend=springs,
                  pinned="edge", self_collision=False)
    return gusty(Scene(bodies=[cloth], terrains=[], drag=0.1))


def keyed():
    """The tilted plane's landing cube in a wind keyed to turn within the run (the second key
    between steps, away from a stage's time: the interpolation has a kink at a key)."""
    scene = tilted_scene("lands and slides")
    scene.wind = Wind(keyframes=[WindKey(0.0, (2.0, 0.0, 1.0)), WindKey(0.0113, (-6.0, 4.0, 2.0))],
                      density=1.2, drag=1.5, friction=0.1, gusts=Gusts(strength=0.3, length=0.8,
                                                                       seed=2))
    return scene


def balls_in_wind():
    """The flag and two balls of different sizes thrown up beside it, in its gusty wind."""
    scene = flag()
    scene.bodies.append(Balls(balls=[
        Ball(position=(2.0, 2.0, 0.0), velocity=(0.5, 3.0, -1.0), radius=0.2, mass=0.3),
        Ball(position=(-2.0, 1.0, 0.5), velocity=(-1.0, 2.0, 4.0), radius=0.35, mass=0.5)]))
    return scene


SCENES = {"cube": lambda: gusty(small_scene()), "flag": flag, "keyed": keyed,
          "balls": balls_in_wind}
NAMES = {"cube": WIND_KEYS, "flag": ["wind.velocity", "bodies.0.structural.ks"],
         "keyed": ["wind.keyframes.1.velocity", "wind.keyframes.1.time",
                   "terrains.0.friction"],
         "balls": ["wind.velocity", "wind.density", "wind.drag", "wind.gusts.strength",
                   "wind.gusts.length", "bodies.1.balls.0.velocity", "bodies.1.balls.1.mass"]}


@pytest.mark.parametrize("case", list(SCENES))
@pytest.mark.parametrize("integrator", list(STEPS))
def test_wind_gradients_match_finite_differences(integrator, case):
    assert_gradients_match(SCENES[case], integrator, NAMES[case])


def test_wind_terms_match_the_kernels():
    """The NumPy wind (the adjoint's) against the simulation's kernels, force and blocks, on a
    gusty cloth and two balls at an arbitrary time."""
    from springsim.gradients.physics import Physical
    from springsim.gradients.clock import FORCE_TIME
    from springsim.gradients.wind import wind_blocks, wind_forces
    from springsim.implicit.pattern import diagonal_pattern
    from springsim.model import build_model
    from springsim.wind import add_wind_forces, add_wind_with_jacobian

    model = build_model(balls_in_wind())
    rng = np.random.default_rng(4)
    x = model.initial_positions + rng.normal(0.0, 0.02, model.initial_positions.shape)
    v = rng.normal(0.0, 1.0, x.shape)
    t, h = 0.37, 0.01
    model.arrays.clock[2] = t
    physical = Physical.of(model)
    physical.clock[FORCE_TIME] = t
    force = np.zeros_like(x)
    add_wind_forces(model.arrays, x, v, np.ones(1), force)
    np.testing.assert_allclose(wind_forces(physical, x, v), force, rtol=1e-12, atol=1e-14)
    pattern = diagonal_pattern(len(x))
    blocks, impulse = np.zeros((len(x), 3, 3)), np.zeros_like(x)
    add_wind_with_jacobian(model.arrays, pattern.diagonal_slot, x, v, h, impulse, blocks)
    np.testing.assert_allclose(wind_blocks(physical, x, v, h), blocks[pattern.diagonal_slot],
                               rtol=1e-12, atol=1e-14)


def test_fit_recovers_the_wind(tmp_path, capsys):
    """`springsim fit --fit wind.velocity`: a flag's take in a 6 m/s gusty wind, fitted from
    a wind of (2, 1, 3) m/s, gives the wind back."""
    import json

    from springsim.cli import main
    from springsim.scenefile import scene_to_toml

    scene = flag()
    scene.wind.velocity = (0.0, 0.0, 6.0)
    scene.bodies[0].rotation_degrees = 90.0   # hanging, face to the wind
    scene_file = tmp_path / "flag.toml"
    scene_file.write_text(scene_to_toml(scene))
    options = ["--integrator", "implicit_euler", "--dt", "0.01"]
    take = tmp_path / "take.npz"
    assert main(["run", str(scene_file), *options, "--duration", "0.5", "--fps", "50",
                 "--out", str(take), "--quiet"]) == 0
    assert main(["fit", str(scene_file), *options, "--observed", str(take), "--fit",
                 "wind.velocity", "--set", "wind.velocity=[2.0,1.0,3.0]",
                 "--out", str(tmp_path / "fitted.toml")]) == 0
    answer = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    np.testing.assert_allclose(answer["fitted"]["wind.velocity"], [0.0, 0.0, 6.0], atol=1e-3)
