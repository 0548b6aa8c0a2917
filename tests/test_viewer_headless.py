"""The viewer run headless (polyscope's EGL backend): its real per-frame callback, panel included.

Oracles: many frames advance the simulation by exactly frames x steps-per-frame steps, and the
cube falls as g t^2 / 2 says while it is in the air; the drawing follows the controls (toggles
show and hide structures, a rebuilt cube is drawn with its new surface); a diverging setting
stops the run, shows the course's red message in the panel (red pixels appear in the screenshot)
and the window lives on, a reset recovers; Ctrl + drag with the mouse (ImGui events, as a window
would send them) grabs the particle under the cursor and pulls it towards the cursor; the Record
button writes the frames shown, and its last frame is what the screen shows; the contacts toggle
draws the contacts between two stacked cubes where they touch, and a bad thickness shows its
message while the window lives on.
"""
import numpy as np
import polyscope as ps
import polyscope.imgui as psim
import pytest

from springsim.bodies.cube import Cube
from springsim.render import Camera, capture, start_renderer
from springsim.render.contacts import contact_marks
from springsim.scene import Scene
from springsim.springs import SpringKind
from springsim.terrains import Plane
from springsim.viewer.controls import UNSTABLE_MESSAGE, Controls
from springsim.viewer.panel import draw_toggles
from springsim.viewer.window import Viewer

WIDTH, HEIGHT = 480, 320
GRAVITY = 9.8


@pytest.fixture(scope="module")
def viewer():
    start_renderer(headless=True, width=WIDTH, height=HEIGHT)   # once per process, shared
    viewer = Viewer(Controls("jelly-plane"), headless=True, width=WIDTH, height=HEIGHT)
    yield viewer
    ps.clear_user_callback()


def red_pixels(picture: np.ndarray) -> int:
    r, g, b = (picture[..., c].astype(int) for c in range(3))
    return int(np.count_nonzero((r > 200) & (g < 90) & (b < 90)))


def test_frames_advance_the_simulation_and_the_drawing(viewer):
    controls = viewer.controls
    controls.choose_scene("jelly-plane")
    controls.start()
    y0 = controls.sim.positions[:, 1].mean()
    viewer.run(frames=30)
    sim = controls.sim
    assert sim.steps_taken == 30 * controls.steps_per_frame
    t = sim.time
    assert t == pytest.approx(30 * controls.steps_per_frame * 1e-3)
    # still in the air: every particle falls freely (springs at rest length)
    assert sim.positions[:, 1].mean() == pytest.approx(y0 - GRAVITY * t * t / 2, abs=1e-6)
    assert np.array_equal(viewer.drawing.positions, sim.positions)
    assert controls.stats.fps > 0 and controls.stats.steps_per_second > 0


def test_control_changes_reach_the_drawing(viewer):
    controls = viewer.controls
    controls.choose_scene("jelly-plane")
    viewer.run(frames=1)
    structural = ps.get_curve_network("springs: structural")
    assert not structural.is_enabled()
    viewer.set_drawn("structural", True)
    viewer.set_drawn("surfaces", False)
    assert structural.is_enabled() and not ps.get_surface_mesh("surface 0: cube0").is_enabled()
    before = capture()
    cyan = np.count_nonzero((before[..., 0] < 80) & (before[..., 1] > 150) & (before[..., 2] > 150))
    assert cyan > 50                                      # the structural springs are cyan
    viewer.set_drawn("structural", False)
    viewer.set_drawn("surfaces", True)

    assert controls.set_particles_per_edge(4)
    assert controls.choose_terrain("bowl")
    assert controls.set_spring(SpringKind.BEND, ks=500.0)
    viewer.run(frames=2)
    # a 4 x 4 x 4 cube has 64 - 2^3 = 56 particles on its surface
    assert ps.get_surface_mesh("surface 0: cube0").n_vertices() == 56
    assert ps.has_surface_mesh("terrain 0: bowl") and not ps.has_surface_mesh("terrain 0: plane")


def test_divergence_shows_the_red_message_and_the_viewer_lives_on(viewer):
    controls = viewer.controls
    controls.choose_scene("jelly-plane")
    controls.set_particles_per_edge(4)
    controls.set_cube_height(3.0)
    viewer.run(frames=1)
    assert red_pixels(capture(include_ui=True)) == 0
    controls.set_integrator("explicit_euler")
    controls.set_dt(0.01)
    controls.start()
    for _ in range(60):
        viewer.run(frames=1)
        if controls.unstable:
            break
    assert controls.unstable and controls.message.startswith(UNSTABLE_MESSAGE)
    viewer.run(frames=3)                                  # the window goes on
    assert red_pixels(capture(include_ui=True)) > 50
    assert not controls.running

    controls.set_integrator("rk4")
    controls.set_dt(1e-3)
    controls.start()                                      # Start resets
    viewer.run(frames=5)
    assert not controls.unstable and controls.sim.time == pytest.approx(
        5 * controls.steps_per_frame * 1e-3)
    assert red_pixels(capture(include_ui=True)) == 0


def view_camera() -> Camera:
    """polyscope's current view as a pinhole camera."""
    params = ps.get_view_camera_parameters()
    eye = np.asarray(params.get_position(), float)
    return Camera(eye=eye, target=eye + np.asarray(params.get_look_dir(), float),
                  up=tuple(params.get_up_dir()), fov_degrees=ps.get_vertical_fov_degrees())


def test_ctrl_drag_pulls_the_particle_under_the_cursor(viewer):
    controls = viewer.controls
    controls.choose_scene("jelly-plane")
    controls.set_particles_per_edge(5)
    controls.set_cube_height(1.5)                         # resting on the plane
    viewer.run(frames=1)
    x = controls.sim.positions
    top_centre = (x[:, 0].mean(), x[:, 1].max(), x[:, 2].mean())   # a particle in plain sight
    top = int(np.argmin(np.linalg.norm(x - top_centre, axis=1)))
    column, row = view_camera().project(x[top], WIDTH, HEIGHT)[0]
    offset_before = x[top, 1] - x[:, 1].mean()

    io = psim.GetIO()
    io.AddKeyEvent(psim.ImGuiMod_Ctrl, True)
    io.AddMousePosEvent(float(column), float(row))
    viewer.run(frames=1)
    io.AddMouseButtonEvent(0, True)
    viewer.run(frames=1)
    assert controls.mouse.holding
    held = controls.mouse.particle
    assert np.linalg.norm(x[held] - x[top]) < 1.5 * viewer.drawing.spacing
    controls.resume()
    for lift in range(1, 16):                            # drag upwards on the screen
        io.AddMousePosEvent(float(column), float(row - 4 * lift))
        viewer.run(frames=1)
    x = controls.sim.positions
    assert controls.mouse.target[1] > x[held, 1] > x[top, 1] - 0.05
    assert x[held, 1] - x[:, 1].mean() > offset_before + 0.1   # pulled out of the cube's shape
    io.AddMouseButtonEvent(0, False)
    io.AddKeyEvent(psim.ImGuiMod_Ctrl, False)
    viewer.run(frames=1)
    assert not controls.mouse.holding


def test_record_button_writes_the_frames_on_screen_to_an_mp4(viewer, tmp_path):
    import imageio.v2 as imageio_v2

    controls = viewer.controls
    controls.choose_scene("jelly-plane")
    controls.start()
    viewer.recorder.folder = tmp_path
    # a clock that advances one video frame per reading: one drawn frame, one video frame
    ticks = iter(range(1000))
    viewer.recorder.clock = lambda: next(ticks) / viewer.recorder.fps
    viewer.start_recording()
    viewer.run(frames=8)
    on_screen = capture()
    path = viewer.stop_recording()
    assert path.parent == tmp_path and path.suffix == ".mp4"
    with imageio_v2.get_reader(path) as reader:
        frames = [frame for frame in reader]
    assert len(frames) == 8 and frames[-1].shape == (HEIGHT, WIDTH, 3)
    # H.264 is lossy: the last frame matches the screen to within compression noise
    assert np.abs(frames[-1].astype(int) - on_screen).mean() < 4


def stacked_cubes() -> Scene:
    """Two 4 m cubes of 3 x 3 x 3 particles, the upper one's bottom face 3 cm above the lower
    one's top face (y = 4.5 m): closer than their thickness, 5 cm."""
    return Scene(name="two cubes", terrains=[Plane()], bodies=[
        Cube(particles_per_edge=3, position=(0.0, 2.5, 0.0)),
        Cube(particles_per_edge=3, position=(0.0, 6.53, 0.0))])


def run_panel_sections(viewer) -> None:
    """One frame that builds the body-contact controls and the draw toggles (the panel keeps
    them in a closed section) in a window of their own."""
    c = viewer.controls

    def sections():
        psim.Begin("sections under test")
        viewer.panel._body_contact()
        draw_toggles(c.draw, c.sim.model, viewer.set_drawn, contacts=True)
        psim.End()

    ps.set_user_callback(sections)
    viewer.run(frames=1)
    ps.set_user_callback(viewer.frame)


def test_contacts_toggle_draws_the_contacts_where_the_cubes_touch(viewer):
    controls = viewer.controls
    assert controls.choose_scene(stacked_cubes())
    viewer.set_drawn("contacts", True)
    viewer.run(frames=1)
    x = controls.sim.positions
    marks = contact_marks(controls.sim.model.arrays, x)
    cloud = ps.get_point_cloud("contacts")
    assert cloud.is_enabled() and cloud.n_points() == len(marks.points) > 0
    top_of_lower = x[:27, 1].max()
    assert np.all(np.abs(marks.points[:, 1] - top_of_lower) < 0.05)   # between the cubes
    run_panel_sections(viewer)

    sim = controls.sim
    assert not controls.set_thickness(1, 1.5)             # beyond 1 m: refused, not a crash
    viewer.run(frames=2)
    assert controls.sim is sim and controls.message.startswith("bodies.1.thickness = 1.5")
    assert controls.set_thickness(1, 0.005) and controls.message == ""
    viewer.run(frames=1)                                  # 3 cm apart: beyond (5 + 0.5) / 2 cm
    assert ps.get_point_cloud("contacts").n_points() == 0
    viewer.set_drawn("contacts", False)
    assert not ps.get_point_cloud("contacts").is_enabled()
