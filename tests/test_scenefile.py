"""Scene files and overrides.

Oracles: a TOML file that says what a preset says builds the very same model; every preset
written out (in full or only its changes) and read back builds the same model; the examples in
docs/scene-files.md build their presets' models; an override changes exactly the key it names;
bad input is refused with a SceneError naming the key, the value and what is allowed.
"""
import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from springsim import Simulation, load_scene
from springsim.errors import SceneError
from springsim.model import build_model
from springsim.presets import PRESETS, preset
from springsim.scene import Scene
from springsim.scenefile import BODY_TYPES, scene_to_toml, toml_value
from springsim.terrains import TERRAIN_TYPES

DOC = Path(__file__).resolve().parents[1] / "docs" / "scene-files.md"
README = Path(__file__).resolve().parents[1] / "README.md"

# The jelly-plane preset, every key written out, in the different ways TOML allows.
JELLY_PLANE_TOML = """
name = "jelly-plane"
integrator = "rk4"
dt = 0.001
duration = 8
gravity = [0, -9.8, 0]
drag = 0

[[bodies]]
type = "cube"
particles_per_edge = 10
edge_length = 4
particle_mass = 1
position = [0, 9, 0]
velocity = [0, 0, 0]
rotation_degrees = 0
rotation_axis = [1, 0, 1]
face_springs = false
pinned = []
structural = {ks = 2000, kd = 60}
[bodies.shear]
ks = 2000
kd = 60
[bodies.bend]
ks = 2000.0
kd = 60.0

[[terrains]]
type = "plane"
point = [0, -1, 0]
normal = [0, 1, 0]
restitution = 0.8
friction = 0.3
epsilon = 0.01
"""


def assert_same_values(a, b, name):
    """Arrays equal, and the terms' tables (tuples of named tuples of arrays) field by field."""
    if isinstance(a, tuple):
        assert isinstance(b, tuple) and len(a) == len(b), name
        for part, (first, second) in enumerate(zip(a, b)):
            assert_same_values(first, second, f"{name}[{part}]")
        return
    np.testing.assert_array_equal(a, b, err_msg=name)


def assert_same_model(scene_a, scene_b):
    for name in ("name", "integrator", "dt", "duration"):
        assert getattr(scene_a, name) == getattr(scene_b, name), name
    a, b = build_model(scene_a), build_model(scene_b)
    for name in a.arrays._fields:
        assert_same_values(getattr(a.arrays, name), getattr(b.arrays, name), name)
    for name in ("mass", "pinned", "spring_kind", "initial_positions", "initial_velocities"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def write(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def flatten(value, prefix=""):
    """{dotted key: value} for every leaf of a scene (list items and vector components by
    index), the way overrides address them."""
    if dataclasses.is_dataclass(value):
        items = {field.name: getattr(value, field.name) for field in dataclasses.fields(value)}
    elif isinstance(value, (list, tuple)):
        items = dict(enumerate(value))
    else:
        return {prefix: value}
    leaves = {}
    for name, item in items.items():
        leaves.update(flatten(item, f"{prefix}.{name}" if prefix else str(name)))
    return leaves


def test_a_toml_file_saying_what_the_preset_says_builds_the_same_model(tmp_path):
    scene = load_scene(write(tmp_path, JELLY_PLANE_TOML))
    assert_same_model(scene, preset("jelly-plane"))


@pytest.mark.parametrize("name", list(PRESETS))
def test_every_preset_written_out_and_read_back_builds_the_same_model(tmp_path, name):
    for only_changes in (False, True):
        text = scene_to_toml(preset(name), only_changes=only_changes)
        assert_same_model(load_scene(write(tmp_path, text, f"{name}.toml")), preset(name))


def documented_examples():
    """{preset name: TOML text} for every example in the docs that says which preset it is."""
    blocks = re.findall(r"```toml\n(.*?)```", DOC.read_text(), re.S)
    return {match.group(1): block for block in blocks
            if (match := re.match(r"# the (\S+) preset", block))}


def test_the_documented_examples_build_their_presets(tmp_path):
    examples = documented_examples()
    assert examples, "docs/scene-files.md shows no preset example"
    for name, text in examples.items():
        assert_same_model(load_scene(write(tmp_path, text, f"{name}.toml")), preset(name))
    text = DOC.read_text() + README.read_text()
    assert all(f"`{name}`" in text or name in examples for name in PRESETS)


def all_tables():
    """Every dataclass a scene file can describe, reached from the registries' defaults."""
    seen, pending = [], [Scene(), *(cls() for cls in BODY_TYPES.values()),
                         *(factory() for factory in TERRAIN_TYPES.values())]
    while pending:
        example = pending.pop()
        if type(example) in seen:
            continue
        seen.append(type(example))
        for field in dataclasses.fields(example):
            value = getattr(example, field.name)
            values = value if isinstance(value, (list, tuple)) else [value]
            pending += [item for item in values if dataclasses.is_dataclass(item)]
    return seen


def test_the_documentation_names_every_key_a_file_can_say():
    """Every field of every table a scene file can describe is a key of the site's scene-file
    reference, which the documentation's hook generates (docs/hooks/reference.py)."""
    from test_docs import hook

    text = hook.scene_reference_markdown()
    missing = [f"{cls.__name__}.{field.name}" for cls in all_tables()
               for field in dataclasses.fields(cls) if f".{field.name}`" not in text
               and f"`{field.name}`" not in text]
    assert not missing, "the scene-file reference does not describe " + ", ".join(missing)


OVERRIDES = {"bodies.0.particles_per_edge": 7, "bodies.0.structural.ks": 1234.0,
             "bodies.0.face_springs": True, "terrains.0.friction": 0.5, "dt": 0.0005,
             "gravity.1": -1.62, "integrator": "midpoint"}


def test_overrides_change_exactly_the_keys_they_name():
    before = flatten(preset("jelly-plane"))
    after = flatten(load_scene("jelly-plane", [f"{key}={toml_value(value)}"
                                               for key, value in OVERRIDES.items()]))
    changed = {key for key in before.keys() | after.keys() if before.get(key) != after.get(key)}
    assert changed == set(OVERRIDES)
    assert all(after[key] == value and type(after[key]) is type(value)
               for key, value in OVERRIDES.items())


def test_whole_values_bare_words_and_python_numbers_override_the_same_way():
    by_parts = load_scene("jelly-plane", ["gravity.1=-1.62", "integrator=midpoint", "dt=5e-4"])
    whole = load_scene("jelly-plane", ["gravity=[0, -1.62, 0]", 'integrator="midpoint"',
                                       "dt=.0005"])
    assert by_parts == whole


def test_a_partial_sub_table_keeps_the_other_keys_of_the_default(tmp_path):
    scene = load_scene(write(tmp_path, '[[bodies]]\ntype = "cube"\n[bodies.bend]\nks = 10\n'),
                       ["bodies.0.shear={kd=1}"])
    cube = scene.bodies[0]
    assert (cube.bend.ks, cube.bend.kd) == (10.0, preset("jelly-plane").bodies[0].bend.kd)
    assert (cube.shear.ks, cube.shear.kd) == (preset("jelly-plane").bodies[0].shear.ks, 1.0)


def test_an_override_may_set_a_key_the_file_leaves_out_and_the_name_is_the_file_s(tmp_path):
    scene = load_scene(write(tmp_path, '[[bodies]]\ntype = "cube"\n', "drop.toml"),
                       ["drag=0.25", "bodies.0.position.1=3"])
    assert (scene.name, scene.drag, scene.bodies[0].position) == ("drop", 0.25, (0.0, 3.0, 0.0))


CUBE = '[[bodies]]\ntype = "cube"\n'
BAD_FILES = [  # (file text, key, value, a fragment of what is allowed)
    (CUBE + "particle_per_edge = 5", "bodies.0.particle_per_edge", 5, "particles_per_edge"),
    ("gravty = [0, -9.8, 0]\n" + CUBE, "gravty", [0, -9.8, 0], "gravity"),
    ('dt = "fast"\n' + CUBE, "dt", "fast", "number"),
    ("drag = true\n" + CUBE, "drag", True, "number"),
    (CUBE + "particles_per_edge = 4.5", "bodies.0.particles_per_edge", 4.5, "whole number"),
    ("gravity = [0, -9.8]\n" + CUBE, "gravity", [0, -9.8], "3"),
    (CUBE + "position = [0, 1, 2, 3]", "bodies.0.position", [0, 1, 2, 3], "3"),
    (CUBE + "particle_mass = -1", "bodies.0.particle_mass", -1, "> 0"),
    ("dt = 0\n" + CUBE, "dt", 0, "> 0"),
    ("dt = -0.001\n" + CUBE, "dt", -0.001, "> 0"),
    (CUBE + "particles_per_edge = 1", "bodies.0.particles_per_edge", 1, ">= 2"),
    (CUBE + "[bodies.structural]\nks = 'stiff'", "bodies.0.structural.ks", "stiff", "number"),
    (CUBE + "[bodies.structural]\nkz = 1", "bodies.0.structural.kz", 1, "ks, kd"),
    ('[[bodies]]\ntype = "blob"', "bodies.0.type", "blob", "cube"),
    ("[[bodies]]\nparticles_per_edge = 3", "bodies.0.type", None, "cube"),
    (CUBE + '[[terrains]]\ntype = "cliff"', "terrains.0.type", "cliff", "bowl"),
    (CUBE + '[[terrains]]\ntype = "plane"\nfriction = -1', "terrains.0.friction", -1, ">= 0"),
    (CUBE + '[[terrains]]\ntype = "bowl"\nradius = "big"', "terrains.0.radius", "big",
     "number"),
    ('integrator = "leapfrog"\n' + CUBE, "integrator", "leapfrog", "rk4"),
    ("bodies = []", "bodies", [], "at least one body"),
]


@pytest.mark.parametrize("text, key, value, allowed", BAD_FILES)
def test_a_bad_scene_file_is_refused_naming_key_value_and_what_is_allowed(
        tmp_path, text, key, value, allowed):
    with pytest.raises(SceneError) as error:
        load_scene(write(tmp_path, text))
    assert (error.value.key, error.value.value) == (key, value)
    assert allowed in error.value.allowed


BAD_OVERRIDES = [  # (override, key, value, a fragment of what is allowed)
    ("bodies.0.nope=1", "bodies.0.nope", 1, "particles_per_edge"),
    ("bodies.3.particles_per_edge=4", "bodies.3.particles_per_edge", 4, "index must be 0"),
    ("terrains.0.friction.x=1", "terrains.0.friction.x", 1, "single value"),
    ("gravity.3=1", "gravity.3", 1, "0 to 2"),
    ("bodies.0.particles_per_edge=seven", "bodies.0.particles_per_edge", "seven",
     "whole number"),
    ("bodies.0.pinned=[1, 5000]", "bodies.0.pinned", 5000, "[0, 999]"),
    ("terrains.0.restitution=2", "terrains.0.restitution", 2, "[0, 1]"),
    ("dt", "--set", "dt", "KEY=VALUE"),
]


@pytest.mark.parametrize("override, key, value, allowed", BAD_OVERRIDES)
def test_a_bad_override_is_refused_naming_the_full_key(override, key, value, allowed):
    with pytest.raises(SceneError) as error:
        load_scene("jelly-plane", [override])
    assert (error.value.key, error.value.value) == (key, value)
    assert allowed in error.value.allowed


def test_a_body_starting_inside_a_terrain_is_refused_before_simulating():
    with pytest.raises(SceneError) as error:
        Simulation(load_scene("jelly-plane", ["bodies.0.position=[0, -3, 0]"]))
    assert error.value.key == "bodies.0.position" and "inside terrains.0" in error.value.allowed


def test_an_unreadable_scene_file_is_refused(tmp_path):
    cases = [(write(tmp_path, "dt = = 1"), "not valid TOML"),
             (str(tmp_path / "missing.toml"), "no such file"),
             ("jely-plane", "one of jelly-plane")]
    for name, allowed in cases:
        with pytest.raises(SceneError) as error:
            load_scene(name)
        assert (error.value.key, error.value.value) == ("scene", name)
        assert allowed in error.value.allowed


def test_a_ball_starting_inside_a_terrain_is_named_by_its_own_key():
    scene = load_scene("jelly-balls", ["bodies.1.balls.2.position=[0, -1, 0]"])
    with pytest.raises(SceneError, match=r"bodies\.1\.balls\.2\.position = \(0\.0, -1\.0, 0\.0\)"):
        Simulation(scene)


def test_an_unset_thickness_stays_unset_through_a_file(tmp_path):
    """A cloth's thickness left unset is written as no key, so that read back and refined to
    200 x 200 (spacing 2 cm) its thickness still follows the spacing and the self-colliding
    cloth is accepted; a thickness set to 2 cm is kept, and refused there (it must stay below
    half the spacing)."""
    for thickness, accepted in ((None, True), (0.02, False)):
        scene = preset("cloth-hang")
        scene.bodies[0].thickness = thickness
        path = write(tmp_path, scene_to_toml(scene), "cloth.toml")
        if accepted:
            cloth = load_scene(path, ["bodies.0.particles_per_edge=200"]).bodies[0]
            assert cloth.thickness is None
            assert 0 < cloth.contact_thickness() < 0.5 * cloth.surface_spacing()
        else:
            with pytest.raises(SceneError, match="bodies.0.thickness"):
                load_scene(path, ["bodies.0.particles_per_edge=200"])
