"""Gradients under the other explicit methods (gradients/adjoints.py): explicit_euler, midpoint
(its second force evaluation half way through the step) and predict_reevaluate (its second at
the step's end, the terrain's contact there stopping the start's velocity, not the
prediction's), against central finite differences of the forward run: the small cube's scene
keys, the cube landing and sliding on the tilted plane and resting on it, and the cube resting
on the platform that slides and turns under it (each evaluation sees it where it is then)."""
import pytest

import test_gradients as base
from test_gradients import (SCENE_KEYS, assert_gradients_match, small_scene,
                            test_terrain_contact_matches_finite_differences as contact_case)
from test_gradients_moving import platform

OTHERS = {"explicit_euler": 0.001, "midpoint": 0.002, "predict_reevaluate": 0.002}


@pytest.fixture(autouse=True)
def their_steps(monkeypatch):
    """The step of each method, beside test_gradients' own (STEPS)."""
    for name, dt in OTHERS.items():
        monkeypatch.setitem(base.STEPS, name, dt)


@pytest.mark.parametrize("integrator", list(OTHERS))
def test_scene_keys_match_finite_differences(integrator):
    assert_gradients_match(small_scene, integrator, SCENE_KEYS)


@pytest.mark.parametrize("case", list(base.CONTACT_CASES))
@pytest.mark.parametrize("integrator", list(OTHERS))
def test_terrain_contact_matches_finite_differences(integrator, case):
    contact_case(integrator, case)


@pytest.mark.parametrize("integrator", list(OTHERS))
def test_a_moving_terrain_matches_finite_differences(integrator):
    assert_gradients_match(platform, integrator, ["terrains.0.friction",
                                                  "bodies.0.structural.ks", "gravity",
                                                  "bodies.0.velocity"])
