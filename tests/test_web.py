"""`springsim play --web`: the replay served by viser, seen by a real headless browser.

Oracles: the server's scene holds, for the frame shown, exactly the recorded positions (the body
mesh's vertices, the balls' centres), seeking and toggles change them and their visibility, and
Debian's chromium, loading the page from the running command, draws the body: the orange cube's
pixels fill part of the middle of the screenshot.
"""
import base64
import contextlib
import itertools
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request

import imageio.v3 as iio
import numpy as np
import pytest
from websockets.sync.client import connect

from springsim.export import load_take
from springsim.export.geometry import body_pieces
from test_replay import take_path  # noqa: F401  (the same recording: jelly-balls, 1 s at 20 fps)

pytestmark = pytest.mark.external   # the external tier (conftest.py): Chromium


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_the_server_holds_the_recorded_positions_of_the_frame_shown(take_path):
    from springsim.replay.web import WebReplay

    take = load_take(take_path)
    replay = WebReplay(take, port=free_port())
    try:
        cube = body_pieces(take.layout, take.positions[0])[0]
        parts = {toggle: [] for toggle, _, _ in replay._parts}
        for toggle, handle, _ in replay._parts:
            parts[toggle].append(handle)
        for frame in (0, 9, take.frame_count - 1):
            replay._seek(frame)
            np.testing.assert_allclose(parts["surfaces"][0].vertices,
                                       cube.vertices(take.positions[frame]), atol=1e-6)
            centres = [ball.position for ball in parts["balls"]]
            np.testing.assert_allclose(centres, take.positions[frame, take.layout.ball_particles])
            assert replay.frame_slider.value == frame + 1   # numbered from 1, as "frame 1 of N"
        replay.frame_slider.value = 5                       # the slider at 5: frame 5 of N
        assert replay.timeline.frame == 4
        replay.set_drawn("structural", True)
        assert parts["structural"][0].visible
        replay.set_drawn("surfaces", False)
        assert not parts["surfaces"][0].visible
    finally:
        replay.stop()


def test_the_pins_and_the_wind_are_recorded_and_drawn_where_they_are(tmp_path):
    """A cloth held at its corners in a wind that turns from +x to +z: the recording keeps which
    particles are pinned and the wind's keys, and the browser replay draws a dot on each pinned
    particle where the frame has it and an arrow along the mean wind at the frame's time."""
    from springsim import Simulation
    from springsim.bodies.cloth import Cloth
    from springsim.recording import record, write_npz
    from springsim.replay.web import WebReplay
    from springsim.scene import Scene
    from springsim.wind import Wind, WindKey

    wind = Wind(keyframes=[WindKey(0.0, (4.0, 0.0, 0.0)), WindKey(0.4, (0.0, 0.0, 4.0))])
    scene = Scene(bodies=[Cloth(particles_per_edge=6, width=1.0, height=1.0)], terrains=[],
                  wind=wind, integrator="symplectic_euler", dt=1e-4)
    simulation = Simulation(scene)
    pinned = np.flatnonzero(simulation.model.pinned)
    write_npz(tmp_path / "take.npz", record(simulation, 0.5, 10.0).arrays())
    take = load_take(tmp_path / "take.npz")
    assert len(pinned) == 4 and np.array_equal(take.layout.pinned, pinned)
    assert np.array_equal(take.layout.wind_keys, [[0.0, 4.0, 0.0, 0.0], [0.4, 0.0, 0.0, 4.0]])
    replay = WebReplay(take, port=free_port())
    try:
        handles = {toggle: handle for toggle, handle, _ in replay._parts}
        for frame, way in ((0, [1.0, 0.0, 0.0]), (2, np.array([1.0, 0.0, 1.0]) / np.sqrt(2)),
                           (5, [0.0, 0.0, 1.0])):
            replay._seek(frame)
            np.testing.assert_allclose(handles["pins"].points, take.positions[frame, pinned],
                                       atol=1e-6)
            start, end = np.asarray(handles["wind"].points, float)[0]
            np.testing.assert_allclose((end - start) / np.linalg.norm(end - start), way,
                                       atol=1e-6)
        replay.set_drawn("pins", False)
        assert not handles["pins"].visible
    finally:
        replay.stop()


def test_a_moving_terrain_is_drawn_where_its_motion_has_it_at_the_frames_time(tmp_path):
    """A sphere that slides at 1 m/s and turns under a falling cloth: at each frame shown the
    browser's terrain mesh is the sphere's mesh carried by its motion to the frame's time (its
    centre is the motion's), and a still plane stays where it is."""
    from springsim import Simulation
    from springsim.bodies.cloth import Cloth
    from springsim.export.geometry import terrain_meshes
    from springsim.motion import Motion
    from springsim.recording import record, write_npz
    from springsim.replay.web import WebReplay
    from springsim.scene import Scene
    from springsim.terrains import Plane, Sphere

    ball = Sphere(center=(0.0, 0.5, 0.0), radius=0.3,
                  motion=Motion(velocity=(1.0, 0.0, 0.0), angular_velocity=(0.0, 2.0, 0.0)))
    scene = Scene(bodies=[Cloth(particles_per_edge=4, width=1.0, height=1.0, pinned="none",
                                position=(0.0, 1.2, 0.0))],
                  terrains=[Plane(point=(0.0, -1.0, 0.0)), ball], integrator="implicit_euler",
                  dt=1 / 60)
    write_npz(tmp_path / "take.npz", record(Simulation(scene), 0.5, 10.0).arrays())
    take = load_take(tmp_path / "take.npz")
    plane, sphere = terrain_meshes(take.layout, take.positions)
    replay = WebReplay(take, port=free_port())
    try:
        meshes = [handle for toggle, handle, _ in replay._parts if toggle == "terrains"]
        for frame in (3, 0, take.frame_count - 1):
            replay._seek(frame)
            np.testing.assert_allclose(meshes[0].vertices, plane.vertices, atol=1e-6)
            shown = np.asarray(meshes[1].vertices, float)
            np.testing.assert_allclose(shown, ball.place_at(sphere.vertices, take.time[frame]),
                                       atol=1e-6)
            np.testing.assert_allclose(shown.mean(axis=0), [take.time[frame], 0.5, 0.0],
                                       atol=1e-3)
        replay.set_drawn("terrains", False)              # hidden, moved on, shown again
        replay._seek(1)
        replay.set_drawn("terrains", True)
        np.testing.assert_allclose(meshes[1].vertices,
                                   ball.place_at(sphere.vertices, take.time[1]), atol=1e-6)
    finally:
        replay.stop()


def chromium() -> str:
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found is None:
        if os.environ.get("CI") == "true":
            raise AssertionError("chromium is missing: apt-get install chromium (test.sh does, scripts/system-packages.txt)")
        pytest.skip("chromium is not installed here (apt-get install chromium; test.sh installs it)")
    return found


@contextlib.contextmanager
def served_replay(path):
    """`springsim play TAKE --web` running, paused; yields its URL once it listens."""
    port = free_port()
    server = subprocess.Popen([sys.executable, "-m", "springsim", "play", str(path), "--web",
                               "--port", str(port), "--paused", "--seconds", "300"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 60
        while True:
            assert server.poll() is None, server.stderr.read()
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                assert time.monotonic() < deadline, "the server did not start"
                time.sleep(0.2)
        yield f"http://127.0.0.1:{port}"
    finally:
        server.terminate()
        server.wait(timeout=30)


def test_a_headless_browser_shows_the_body(take_path, tmp_path):
    browser = chromium()
    with served_replay(take_path) as url:
        picture = browser_shot_once(browser, url, tmp_path,
                                    lambda shown: orange_pixels(shown).mean() > 0.01)
    assert picture.shape == (600, 960, 3)
    orange = orange_pixels(picture)
    rows, columns = np.nonzero(orange)
    assert orange.mean() > 0.01
    # where the body is: the camera frames the motion, so the cube lies in the middle third
    assert 960 / 3 < columns.mean() < 2 * 960 / 3 and 600 / 6 < rows.mean() < 5 * 600 / 6


def browser_shot_once(browser, url, folder, shows, seconds=150):
    """A 960 x 600 screenshot (RGB, int) of the page in headless chromium, once `shows` it.

    Driven over the DevTools protocol in real time: the page's scene arrives over a websocket,
    so a one-shot `--screenshot` with a virtual-time budget could come before the mesh or, on a
    loaded machine, never return (a CI run hung 120 s). Here the test looks every half second
    until the picture shows what it waits for, or gives the last picture after `seconds`.
    """
    deadline = time.monotonic() + seconds
    with browser_page(browser, url, folder, deadline) as (call, check_alive):
        while True:
            check_alive()
            png = base64.b64decode(call("Page.captureScreenshot", format="png")["data"])
            picture = iio.imread(png)[..., :3].astype(int)
            if shows(picture) or time.monotonic() > deadline:
                return picture
            time.sleep(0.5)


@contextlib.contextmanager
def browser_page(browser, url, folder, deadline):
    """(call, check_alive) for `url` open in headless chromium at 960 x 600: `call(method,
    **params)` over the page's DevTools websocket; chromium and its children end after."""
    profile, log_path = folder / "profile", folder / "chromium.log"
    with open(log_path, "wb") as log:
        # Port 0: chromium picks a free port itself and names it in the profile (no race with a
        # port chosen here and taken by someone else before chromium binds it). Its own session
        # (process group), so teardown can end its renderer, GPU and zygote children with it.
        process = subprocess.Popen(
            [browser, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
             "--hide-scrollbars", f"--user-data-dir={profile}", "--remote-debugging-port=0",
             "--window-size=960,600", url],
            stdout=subprocess.DEVNULL, stderr=log, start_new_session=True)

    def check_alive():
        # a chromium that died (bad flag, missing library, crash) fails the test now, with its
        # own words, instead of after the whole wait
        assert process.poll() is None, (f"chromium exited with code {process.returncode}:\n"
                                        + log_path.read_text(errors="replace")[-3000:])

    try:
        with devtools_page(devtools_port(profile, deadline, check_alive), deadline,
                           check_alive) as call:
            call("Emulation.setDeviceMetricsOverride", width=960, height=600,
                 deviceScaleFactor=1, mobile=False)
            yield call, check_alive
    finally:
        end_process_group(process)


def end_process_group(process, grace=5):
    """SIGTERM to the process's whole group, then SIGKILL to whatever of it is left after `grace`.

    Killing only the browser process could leave its children running after the test."""
    with contextlib.suppress(ProcessLookupError):  # the group may be gone already
        os.killpg(process.pid, signal.SIGTERM)
    with contextlib.suppress(subprocess.TimeoutExpired):
        process.wait(timeout=grace)
    with contextlib.suppress(ProcessLookupError):  # the browser if it hangs, or a straggling child
        os.killpg(process.pid, signal.SIGKILL)
    process.wait()


def devtools_port(profile, deadline, check_alive):
    """The port chromium chose for `--remote-debugging-port=0`: the first line of the
    DevToolsActivePort file it writes into its profile once DevTools listens."""
    active_port = profile / "DevToolsActivePort"
    while True:
        check_alive()
        with contextlib.suppress(OSError):  # not written yet
            port, newline, _ = active_port.read_text().partition("\n")
            if newline:  # the whole first line is there, not half of it
                return int(port)
        assert time.monotonic() < deadline, "chromium wrote no DevToolsActivePort file"
        time.sleep(0.2)


@contextlib.contextmanager
def devtools_page(debug_port, deadline, check_alive):
    """`call(method, **params)` on chromium's page over its DevTools websocket."""
    while True:
        check_alive()
        try:
            listing_url = f"http://127.0.0.1:{debug_port}/json/list"
            with urllib.request.urlopen(listing_url, timeout=2) as listing:
                page = next(target for target in json.load(listing) if target["type"] == "page")
            break
        except (OSError, StopIteration, ValueError):
            assert time.monotonic() < deadline, "chromium's DevTools did not answer"
            time.sleep(0.2)
    with connect(page["webSocketDebuggerUrl"], max_size=None) as socket_to_page:
        numbers = itertools.count(1)

        def call(method, **params):
            number = next(numbers)
            socket_to_page.send(json.dumps({"id": number, "method": method, "params": params}))
            while True:
                message = json.loads(socket_to_page.recv(timeout=60))
                if message.get("id") == number:
                    assert "error" not in message, f"{method}: {message['error']}"
                    return message["result"]

        yield call


def orange_pixels(picture):
    """Where the cube's lit faces are: orange pixels."""
    r, g, b = picture[..., 0], picture[..., 1], picture[..., 2]
    return (r > 150) & (r - b > 60) & (g > b)


# Run in the page before its own scripts: every text drawn on a canvas of a uPlot chart, with
# where it starts and ends on that canvas (its transform, alignment and measured width applied).
RECORD_CHART_TEXT = """
window.__chartTexts = [];
const fillText = CanvasRenderingContext2D.prototype.fillText;
CanvasRenderingContext2D.prototype.fillText = function (text, x, y, maxWidth) {
  if (this.canvas.closest && this.canvas.closest(".uplot")) {
    const t = this.getTransform(), width = this.measureText(String(text)).width;
    const align = this.textAlign;
    const shift = (align === "right" || align === "end") ? -width
                : align === "center" ? -width / 2 : 0;
    window.__chartTexts.push({text: String(text), align: align,
      rotated: t.b !== 0 || t.c !== 0, left: t.a * (x + shift) + t.e,
      right: t.a * (x + shift + width) + t.e, canvasWidth: this.canvas.width});
  }
  return fillText.apply(this, arguments);
};
"""


def chart_number(text: str) -> float:
    """A tick label as uPlot writes a number ("20,000", "−5", "0.25"); ValueError for a date
    or a time of day ("1/1/70", "12:00am", ":05")."""
    return float(text.replace(",", "").replace("\u2212", "-"))


def test_the_energy_chart_in_chromium_counts_seconds_with_whole_labels(take_path, tmp_path):
    """Issue 28, item 7, as a browser draws it: uPlot read the time series as dates (the time
    axis said "1/1/70 12:00am", ":00", ":05") and cut the energy labels at the canvas's left
    edge ("0,000" for 20,000). Every label chromium draws on the chart is read back: the time
    ticks are seconds within the take, the energy ticks are numbers within reach of the
    recorded energies, and each starts and ends inside its canvas."""
    from springsim.replay.window import recorded_energies

    take = load_take(take_path)
    energies = np.concatenate(list(recorded_energies(take.arrays).values()))
    browser = chromium()
    with served_replay(take_path) as url:
        deadline = time.monotonic() + 150
        with browser_page(browser, url, tmp_path, deadline) as (call, check_alive):
            call("Page.enable")   # without it the script is not run in the reloaded page
            call("Page.addScriptToEvaluateOnNewDocument", source=RECORD_CHART_TEXT)
            call("Page.reload")
            while True:
                check_alive()
                drawn = json.loads(call("Runtime.evaluate",
                                        expression="JSON.stringify(window.__chartTexts || [])",
                                        returnByValue=True)["result"]["value"])
                aligns = {item["align"] for item in drawn}
                if {"center", "right"} <= aligns and len(drawn) >= 6:   # both axes drawn
                    time.sleep(1)   # let the chart finish its first draws
                    drawn = json.loads(call(
                        "Runtime.evaluate", expression="JSON.stringify(window.__chartTexts)",
                        returnByValue=True)["result"]["value"])
                    break
                assert time.monotonic() < deadline, f"the chart drew no axes: {drawn}"
                time.sleep(0.5)
    ticks = [item for item in drawn if item["text"] not in ("t (s)", "J")]
    for item in ticks:   # dates and times of day do not read as numbers
        assert not item["rotated"], item
        try:
            chart_number(item["text"])
        except ValueError:
            raise AssertionError(f"a tick that is not a number: {item['text']!r}") from None
    assert {"t (s)", "J"} <= {item["text"] for item in drawn}   # the axes' names
    seconds = sorted({chart_number(item["text"]) for item in ticks if item["align"] == "center"})
    joules = sorted({chart_number(item["text"]) for item in ticks if item["align"] != "center"})
    assert len(seconds) >= 3 and seconds[0] >= 0 and seconds[-1] <= take.time[-1] + 1e-9
    span = energies.max() - energies.min()
    assert len(joules) >= 3
    assert energies.min() - span <= joules[0] and joules[-1] <= energies.max() + span
    assert max(abs(value) for value in joules) >= 1000   # labels long enough to be cut before
    for item in drawn:   # whole: no label starts left of its canvas or ends right of it
        if not item["rotated"]:   # (the "J" beside the axis is turned a quarter)
            assert -0.5 <= item["left"] and item["right"] <= item["canvasWidth"] + 0.5, item


def test_the_energy_chart_counts_seconds_and_has_room_for_its_labels(take_path):
    """uPlot reads an x series as dates unless its scale says otherwise (the chart showed
    "1/1/70 12:00am"); the energy axis is wide enough for "-200,000" (it showed "0,000")."""
    from springsim.replay.web import ENERGY_AXIS_WIDTH, WebReplay

    replay = WebReplay(load_take(take_path), port=free_port())
    try:
        plot = replay.energy_plot
        assert plot.scales["x"]["time"] is False
        x_axis, y_axis = plot.axes
        assert x_axis["label"] == "t (s)" and y_axis["size"] == ENERGY_AXIS_WIDTH >= 80
    finally:
        replay.stop()
