"""Drawing body-body surface contacts: where the contact points and normals are.

Two single-cell cloths (four particles, two triangles each) placed by hand, so that geometry
gives the answer. Oracles: a point h above a flat triangle of another body touches it at the
point's foot (its vertical projection) with the normal (0, 1, 0), or (0, -1, 0) from below,
while h is below the mean of the two bodies' thicknesses, and the drawn normal is twice that
mean long; bodies apart, or a point just beyond the mean thickness, give no contact; an edge
crossing another's middle touches between their closest points. The drawing shows exactly these
contacts, only while the toggle is on; a replay's model (no contact arrays) draws none.
"""
import numpy as np
import pytest

from springsim.bodies.cloth import Cloth
from springsim.render.contacts import contact_marks, has_body_contact
from springsim.scene import Scene
from springsim.simulation import Simulation
from springsim.springs import SpringParameters

NO_SPRINGS = SpringParameters(0.0, 0.0)
LOWER, UPPER = 0.02, 0.04        # m, the two cloths' thicknesses
REST = (LOWER + UPPER) / 2       # m, the distance contact keeps between them


def two_cells():
    """The model of two one-cell cloths, of thicknesses LOWER and UPPER."""
    cloths = [Cloth(particles_per_edge=2, bend=NO_SPRINGS, self_collision=False, thickness=t,
                    pinned="none") for t in (LOWER, UPPER)]
    return Simulation(Scene(name="two cells", bodies=cloths, terrains=[])).model


def corners(model):
    """(the ends of the lower cloth's diagonal, its other two corners), particle numbers."""
    triangles = model.arrays.surface_triangles
    lower = triangles[model.arrays.particle_body[triangles[:, 0]] == 0]
    shared = sorted(set(lower[0]) & set(lower[1]))
    return shared, sorted(set(lower.ravel()) - set(shared))


def flat_square(model, diagonal, others, ridge=0.0):
    """Positions with the lower cloth on the square [-1, 1]^2 at y = 0, its diagonal lifted by
    ``ridge``; the upper cloth far above, for the test to place."""
    x = np.zeros((model.particle_count, 3))
    x[diagonal] = [(-1.0, ridge, -1.0), (1.0, ridge, 1.0)]
    x[others] = [(-1.0, 0.0, 1.0), (1.0, 0.0, -1.0)]
    x[4:] = [(0.0, 5.0, 0.0), (0.3, 5.0, 0.0), (0.0, 5.0, 0.3), (0.3, 5.0, 0.3)]
    return x


def point_above(height):
    """The upper cloth's first particle ``height`` above the lower cloth's face, well inside
    one triangle (0.85 m from the diagonal); its other particles rise steeply away."""
    model = two_cells()
    diagonal, others = corners(model)
    x = flat_square(model, diagonal, others)
    foot = 0.6 * x[others[0]] + 0.2 * x[diagonal[0]] + 0.2 * x[diagonal[1]]
    x[4] = foot + (0.0, height, 0.0)
    x[5:] = x[4] + [(0.3, 5.0, 0.0), (0.0, 5.0, 0.3), (0.3, 5.0, 0.3)]
    return model, x, foot


@pytest.mark.parametrize("height", [0.005, 0.025, -0.025])
def test_a_point_above_a_triangle_touches_at_its_foot_along_the_face_normal(height):
    model, x, foot = point_above(height)
    marks = contact_marks(model.arrays, x)
    assert len(marks.points) == 1
    side = np.sign(height)
    np.testing.assert_allclose(marks.points[0], foot, atol=1e-12)
    np.testing.assert_allclose(marks.normals[0], (0.0, side, 0.0), atol=1e-12)
    np.testing.assert_allclose(marks.ends[0], foot + (0.0, side * 2 * REST, 0.0), atol=1e-12)


@pytest.mark.parametrize("height", [0.035, 0.5, 3.0])
def test_no_contact_beyond_the_mean_thickness(height):
    model, x, _ = point_above(height)       # 0.035 m: beyond REST, within the search's reach
    marks = contact_marks(model.arrays, x)
    assert marks.points.shape == marks.normals.shape == marks.ends.shape == (0, 3)


def test_an_edge_crossing_a_ridge_touches_between_their_closest_points():
    """The lower cloth folded into a roof along its diagonal (the ridge 1 m above its corners);
    an edge of the upper cloth crosses the ridge's middle at right angles, 1 cm above it."""
    model = two_cells()
    diagonal, others = corners(model)
    x = flat_square(model, diagonal, others, ridge=1.0)
    h = 0.01
    upper_edge = [edge for edge in model.arrays.surface_edges if min(edge) >= 4][0]
    rest = [p for p in range(4, 8) if p not in upper_edge]
    x[upper_edge] = [(-0.5, 1.0 + h, 0.5), (0.5, 1.0 + h, -0.5)]
    x[rest] = [(-0.5, 6.0, 0.5), (0.5, 6.0, -0.5)]
    marks = contact_marks(model.arrays, x)
    assert len(marks.points) == 1
    ridge_middle, edge_middle = np.array([0.0, 1.0, 0.0]), np.array([0.0, 1.0 + h, 0.0])
    other_side = marks.points[0] + h * marks.normals[0]   # the normal spans the gap
    found = sorted([tuple(marks.points[0]), tuple(other_side)], key=lambda p: p[1])
    np.testing.assert_allclose(found, [ridge_middle, edge_middle], atol=1e-12)
    assert np.linalg.norm(marks.ends[0] - marks.points[0]) == pytest.approx(2 * REST)


def test_a_model_without_touching_surfaces_has_no_contacts():
    single = Cloth(particles_per_edge=2, bend=NO_SPRINGS, self_collision=False)
    model = Simulation(Scene(name="one", bodies=[single], terrains=[])).model
    assert not has_body_contact(model)
    assert contact_marks(model.arrays, model.initial_positions).points.shape == (0, 3)
    assert has_body_contact(two_cells())


def test_the_drawing_shows_the_contacts_only_while_toggled_on():
    import polyscope as ps

    from springsim.render import DrawOptions, SceneDrawing, start_renderer

    start_renderer(headless=True, width=160, height=96)
    model, x, _ = point_above(0.01)
    drawing = SceneDrawing(model, DrawOptions(), x)
    assert drawing.structure_names("contacts") == ["contacts"]
    cloud = ps.get_point_cloud("contacts")
    assert not cloud.is_enabled() and cloud.n_points() == 0    # off: not even searched
    drawing.apply_options(DrawOptions.only(["surfaces", "contacts"]))
    cloud, normals = ps.get_point_cloud("contacts"), ps.get_curve_network("contact normals")
    assert cloud.is_enabled() and normals.is_enabled()
    assert cloud.n_points() == 1 and normals.n_nodes() == 2 and normals.n_edges() == 1
    drawing.update(point_above(0.5)[1])
    assert ps.get_point_cloud("contacts").n_points() == 0
    drawing.apply_options(DrawOptions())
    assert not ps.get_point_cloud("contacts").is_enabled()
    assert not ps.get_curve_network("contact normals").is_enabled()


STACKED_CUBES = """
name = "two cubes"
[[terrains]]
type = "plane"
[[bodies]]
type = "cube"
particles_per_edge = 3
position = [0.0, 2.5, 0.0]
[[bodies]]
type = "cube"
particles_per_edge = 3
position = [0.0, 6.53, 0.0]
"""


def test_render_draws_the_contacts_when_asked(tmp_path):
    """`springsim render --draw contacts`: two cubes 3 cm apart (thickness 5 cm) touch; their
    contact points are the only red in the picture."""
    import imageio.v3 as iio

    from springsim.cli import main
    from springsim.render import start_renderer

    start_renderer(headless=True, width=160, height=96)
    scene = tmp_path / "two-cubes.toml"
    scene.write_text(STACKED_CUBES)
    common = ["--duration", "0.05", "--fps", "20", "--width", "160", "--height", "96",
              "--quiet"]
    for draw in ("surfaces", "contacts"):
        assert main(["render", str(scene), "--out", str(tmp_path / draw), "--draw", draw,
                     *common]) == 0
    red = {}
    for draw in ("surfaces", "contacts"):
        picture = iio.imread(tmp_path / draw / "frame_00000.png").astype(int)
        r, g, b = picture[..., 0], picture[..., 1], picture[..., 2]
        red[draw] = int(np.count_nonzero((r > 150) & (g < 80) & (b < 80)))
    assert red["surfaces"] == 0 and red["contacts"] > 20


# -- balls: their contacts are drawn too ---------------------------------------------------------

def ball_and_points(ball_height, second_ball=False):
    """A ball of radius 0.5 m ``ball_height`` above a free point at the origin (and, if
    ``second_ball``, another ball of radius 0.25 m touching the first from beside, 1 cm deep)."""
    from springsim.bodies.balls import Ball, Balls

    balls = [Ball(position=(0.0, ball_height, 0.0), radius=0.5)]
    if second_ball:
        balls.append(Ball(position=(0.74, ball_height, 0.0), radius=0.25))
    points = Cloth(particles_per_edge=2, bend=NO_SPRINGS, self_collision=False, pinned="none",
                   width=10.0, height=10.0, position=(0.0, -50.0, 0.0))
    simulation = Simulation(Scene(name="ball", bodies=[points, Balls(balls=balls)],
                                  terrains=[]))
    x = simulation.positions.copy()
    x[0] = (0.0, 0.0, 0.0)   # one cloth particle under the ball; the others far below
    return simulation.model, x


def test_a_ball_touching_a_point_is_drawn_at_the_point_towards_the_ball():
    model, x = ball_and_points(0.45)
    assert has_body_contact(model)
    marks = contact_marks(model.arrays, x)
    assert len(marks.points) == 1
    np.testing.assert_allclose(marks.points[0], (0.0, 0.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(marks.normals[0], (0.0, 1.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(marks.ends[0], (0.0, 0.25, 0.0), atol=1e-12)   # half the radius
    assert len(contact_marks(model.arrays, ball_and_points(0.55)[1]).points) == 0


def test_two_balls_touching_are_drawn_on_the_second_balls_surface():
    model, x = ball_and_points(3.0, second_ball=True)   # the point is far: balls only
    marks = contact_marks(model.arrays, x)
    assert len(marks.points) == 1
    np.testing.assert_allclose(marks.normals[0], (-1.0, 0.0, 0.0), atol=1e-12)
    np.testing.assert_allclose(marks.points[0], (0.74 - 0.25, 3.0, 0.0), atol=1e-12)
