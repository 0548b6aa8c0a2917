"""The cube's spring lattice: counts from the closed formulas, each pair once, rest lengths equal
to the initial distances (and to the lattice geometry), and clear errors below the N a kind needs.
"""
import numpy as np
import pytest

from springsim import SceneError
from springsim.bodies.cube import Cube
from springsim.model import build_model
from springsim.scene import Scene
from springsim.springs import SpringKind, SpringParameters

NO_SPRINGS = SpringParameters(0.0, 0.0)


def cube_model(n, **options):
    scene = Scene(bodies=[Cube(particles_per_edge=n, **options)])
    scene.validate()
    return build_model(scene)


def expected_counts(n):
    return {SpringKind.STRUCTURAL: 3 * n ** 2 * (n - 1),
            SpringKind.SHEAR: 6 * n * (n - 1) ** 2 + 4 * (n - 1) ** 3,
            SpringKind.BEND: 3 * n ** 2 * (n - 2),
            SpringKind.FACE: 3 * n ** 2}


def lattice_steps(kind, n):
    """Lattice lengths (in spacings) a spring of ``kind`` may have."""
    return {SpringKind.STRUCTURAL: {1.0}, SpringKind.SHEAR: {np.sqrt(2.0), np.sqrt(3.0)},
            SpringKind.BEND: {2.0}, SpringKind.FACE: {n - 1.0}}[kind]


@pytest.mark.parametrize("n", [4, 5, 7, 10, 12])
def test_spring_counts_match_the_formulas(n):
    model = cube_model(n, face_springs=True)
    for kind, count in expected_counts(n).items():
        assert model.spring_count(kind) == count, kind.label
    assert model.spring_count() == sum(expected_counts(n).values())


@pytest.mark.parametrize("n", [2, 3])
def test_small_cubes_build_only_the_kinds_they_can(n):
    bend = SpringParameters(2000.0, 60.0) if n >= 3 else NO_SPRINGS
    model = cube_model(n, bend=bend)
    counts = expected_counts(n)
    assert model.spring_count(SpringKind.STRUCTURAL) == counts[SpringKind.STRUCTURAL]
    assert model.spring_count(SpringKind.SHEAR) == counts[SpringKind.SHEAR]
    assert model.spring_count(SpringKind.BEND) == counts[SpringKind.BEND]
    assert model.spring_count(SpringKind.FACE) == 0


def test_the_default_cube_has_the_framework_counts():
    model = cube_model(10)
    assert (model.spring_count(SpringKind.STRUCTURAL), model.spring_count(SpringKind.SHEAR),
            model.spring_count(SpringKind.BEND)) == (2700, 7776, 2400)


@pytest.mark.parametrize("n", [2, 3, 4, 6, 9])
def test_every_spring_joins_two_particles_once(n):
    options = {"bend": NO_SPRINGS} if n == 2 else {"face_springs": n >= 4}
    springs = cube_model(n, **options).springs.astype(np.int64)
    assert np.all(springs[:, 0] != springs[:, 1])
    pairs = np.sort(springs, axis=1)
    assert len(np.unique(pairs, axis=0)) == len(pairs)


@pytest.mark.parametrize("rotation_degrees", [0.0, 37.0])
def test_rest_lengths_are_the_initial_distances_and_the_lattice_steps(rotation_degrees):
    n, edge = 5, 3.0
    model = cube_model(n, edge_length=edge, face_springs=True,
                       rotation_degrees=rotation_degrees)
    a, b = model.springs[:, 0], model.springs[:, 1]
    x = model.initial_positions
    distance = np.linalg.norm(x[a] - x[b], axis=1)
    np.testing.assert_allclose(model.arrays.rest_length, distance, rtol=0, atol=1e-14)
    spacing = edge / (n - 1)
    for kind in SpringKind:
        lengths = model.arrays.rest_length[model.spring_kind == kind] / spacing
        allowed = np.array(sorted(lattice_steps(kind, n)))
        nearest = np.min(np.abs(lengths[:, None] - allowed[None, :]), axis=1)
        assert nearest.max() < 1e-12, kind.label


def test_each_kind_gets_its_own_stiffness_and_damping():
    model = cube_model(4, structural=SpringParameters(1.0, 2.0), shear=SpringParameters(3.0, 4.0),
                       bend=SpringParameters(5.0, 6.0), face_springs=True,
                       face=SpringParameters(7.0, 8.0))
    arrays = model.arrays
    ks, kd = arrays.group_ks[arrays.spring_group], arrays.group_kd[arrays.spring_group]
    for kind, (stiffness, damping) in {SpringKind.STRUCTURAL: (1, 2), SpringKind.SHEAR: (3, 4),
                                       SpringKind.BEND: (5, 6), SpringKind.FACE: (7, 8)}.items():
        members = model.spring_kind == kind
        assert np.all(ks[members] == stiffness) and np.all(kd[members] == damping), kind.label


@pytest.mark.parametrize("n, options, needs", [
    (1, {}, "integer >= 2"),
    (0, {"bend": NO_SPRINGS}, "integer >= 2"),
    (2, {}, ">= 3 for bend springs"),
    (2, {"bend": NO_SPRINGS, "face_springs": True}, ">= 4 for face springs"),
    (3, {"face_springs": True}, ">= 4 for face springs"),
])
def test_too_few_particles_for_a_kind_is_a_scene_error(n, options, needs):
    with pytest.raises(SceneError) as error:
        cube_model(n, **options)
    assert error.value.key == "bodies.0.particles_per_edge"
    assert error.value.value == n
    assert needs in str(error.value)


@pytest.mark.parametrize("kind", ["structural", "shear", "bend", "face"])
def test_a_cube_refuses_a_spring_stiffness_that_is_not_a_finite_number(kind):
    cube = Cube(**{kind: SpringParameters(ks=float("nan"), kd=60.0)})
    with pytest.raises(SceneError, match=rf"bodies\.0\.{kind}\.ks = nan"):
        cube.validate("bodies.0")


def test_bodies_with_equal_parameters_share_their_groups():
    """One row of the ks/kd tables per distinct (ks, kd), and every spring reads its own kind's
    values from it."""
    soft, stiff = SpringParameters(100.0, 1.0), SpringParameters(900.0, 4.0)
    bodies = [Cube(particles_per_edge=3, position=(3.0 * k, 2.0, 0.0), structural=stiff,
                   shear=soft, bend=soft) for k in range(3)]
    bodies.append(Cube(particles_per_edge=3, position=(0.0, 6.0, 0.0), structural=soft,
                       shear=SpringParameters(50.0, 0.5), bend=soft))
    model = build_model(Scene(bodies=bodies))
    arrays = model.arrays
    assert sorted(zip(arrays.group_ks, arrays.group_kd)) == [(50.0, 0.5), (100.0, 1.0),
                                                             (900.0, 4.0)]
    expected_ks = np.where(model.spring_kind == SpringKind.STRUCTURAL, 900.0, 100.0)
    last = model.springs[:, 0] >= model.bodies[3].start
    expected_ks[last & (model.spring_kind == SpringKind.SHEAR)] = 50.0
    expected_ks[last & (model.spring_kind == SpringKind.STRUCTURAL)] = 100.0
    np.testing.assert_array_equal(arrays.group_ks[arrays.spring_group], expected_ks)
