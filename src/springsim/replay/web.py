"""The replay in a browser: a viser server showing the recording as the viewer does (body
surfaces, balls, terrains, and on request particles and springs), with the same playback controls
(timeline.py) and the run's energy plot. Reach it on a remote machine through a forwarded port, or
inside Jupyter::

    from springsim.replay.web import WebReplay
    replay = WebReplay.open("run.npz", port=8080).start()   # plays in a background thread
    from IPython.display import IFrame; IFrame(replay.url, width=960, height=600)
"""
import threading
import time as clock

import numpy as np

from ..errors import require
from ..export.geometry import body_pieces, terrain_meshes
from ..render import colors
from ..render.drawing import (DrawOptions, WindArrow, has_wind, pinned_particles,
                               typical_spacing)
from ..springs import SpringKind
from .recorded_model import recorded_model
from .timeline import SPEEDS, Timeline
from .window import recorded_energies

TICK = 1 / 30          # s between updates sent to the browser


def rgb(color) -> tuple:
    return tuple(int(round(255 * c)) for c in color)


ENERGY_AXIS_WIDTH = 80   # px: room for "-200,000" in the chart's font


class WebReplay:
    def __init__(self, take, *, host: str = "127.0.0.1", port: int = 8080, speed: float = 1.0,
                 loop: bool = True):
        import viser

        require(0 < port < 65536, "--port", port, "must be a port number from 1 to 65535")
        self.take = take
        self.model = recorded_model(take)
        self.timeline = Timeline(take.time, speed=speed, loop=loop)
        self.draw = DrawOptions()
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.server.scene.set_up_direction("+y")
        self._parts = []            # (toggle name, handle, update(positions) or None)
        self._shown_frame = -1
        self._drawn_time = 0.0      # s: the time of the frame being drawn
        self._thread, self._stop = None, threading.Event()
        self._add_scene()
        self._add_gui()
        self._frame_camera()
        self.show(0)

    @classmethod
    def open(cls, path, **options) -> "WebReplay":
        from ..export import load_take
        return cls(load_take(path), **options)

    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}"

    # --- the scene ----------------------------------------------------------------------------
    def _add_scene(self) -> None:
        scene, first = self.server.scene, self.take.positions[0]
        for number, piece in enumerate(body_pieces(self.take.layout, first)):
            color = colors.BODY_COLORS[number % len(colors.BODY_COLORS)]
            mesh = scene.add_mesh_simple(f"/bodies/{number}", piece.vertices(first).astype(
                np.float32), piece.triangles.astype(np.uint32), color=rgb(color),
                side="front" if piece.closed else "double")
            self._parts.append(("surfaces", mesh, lambda x, m=mesh, p=piece: setattr(
                m, "vertices", p.vertices(x).astype(np.float32))))
        for number, (particle, radius) in enumerate(zip(self.take.layout.ball_particles,
                                                        self.take.layout.ball_radii)):
            ball = scene.add_icosphere(f"/balls/{number}", float(radius), rgb(colors.BALL_COLOR),
                                       position=first[particle])
            self._parts.append(("balls", ball, lambda x, b=ball, i=particle: setattr(
                b, "position", x[i])))
        for name, vertices, triangles, terrain in terrain_meshes(self.take.layout,
                                                                self.take.positions):
            mesh = scene.add_mesh_simple(f"/terrains/{name}", vertices.astype(np.float32),
                                         triangles.astype(np.uint32),
                                         color=rgb(colors.TERRAIN_COLOR), side="double")
            self._parts.append(("terrains", mesh, self._terrain_update(mesh, vertices, terrain)))
        self._add_particles_and_springs(first)
        self._add_pins_and_wind(first)

    def _add_pins_and_wind(self, first) -> None:
        """The pinned particles as dark red dots and the mean wind as an arrow, as the viewer
        draws them (render/drawing.py)."""
        scene, spacing = self.server.scene, typical_spacing(self.model)
        held = np.flatnonzero(pinned_particles(self.model))
        if held.size:
            pins = scene.add_point_cloud("/pins", first[held], rgb(colors.PIN_COLOR),
                                         point_size=0.5 * spacing, point_shape="circle")
            self._parts.append(("pins", pins, lambda x, c=pins, i=held: setattr(
                c, "points", x[i])))
        if has_wind(self.model):
            shape = WindArrow.over(first, self.model.arrays.wind_keys)
            arrow = scene.add_arrows("/wind", self.wind_points(shape, 0), rgb(colors.WIND_COLOR),
                                     shaft_radius=0.03 * shape.length,
                                     head_radius=0.08 * shape.length,
                                     head_length=0.2 * shape.length)
            self._parts.append(("wind", arrow, lambda x, a=arrow, w=shape: setattr(
                a, "points", self.wind_points(w, self.timeline.frame))))

    def _terrain_update(self, mesh, vertices, terrain):
        """For a terrain that moves or deforms, what puts its mesh where it is at the time of
        the frame being drawn; None for a still one."""
        if not terrain.moves():
            return None
        return lambda x: setattr(mesh, "vertices", terrain.vertices_at(
            vertices, self._drawn_time).astype(np.float32))

    def wind_points(self, shape, frame: int) -> np.ndarray:
        """The arrow's (1, 2, 3) start and end at ``frame``'s time."""
        base, arrow = shape.at(float(self.take.time[frame]))
        return np.array([[base, base + arrow]], np.float32)

    def _add_particles_and_springs(self, first) -> None:
        scene, spacing = self.server.scene, typical_spacing(self.model)
        points = np.flatnonzero(self.model.arrays.radius == 0)
        cloud = scene.add_point_cloud("/particles", first[points], rgb(colors.PARTICLE_COLOR),
                                      point_size=0.2 * spacing, point_shape="circle",
                                      visible=False)
        self._parts.append(("particles", cloud, lambda x, c=cloud, i=points: setattr(
            c, "points", x[i])))
        for kind in SpringKind:
            springs = self.model.springs[self.model.spring_kind == kind]
            if not len(springs):
                continue
            lines = scene.add_line_segments(f"/springs/{kind.label}", first[springs],
                                            rgb(colors.SPRING_COLORS[kind]),
                                            thickness=0.03 * spacing, visible=False)
            self._parts.append((kind.label, lines, lambda x, l=lines, s=springs: setattr(
                l, "points", x[s])))

    def _frame_camera(self) -> None:
        from ..render.follow import still_camera

        stride = max(1, self.take.frame_count // 50)
        camera = still_camera("auto", self.model, self.take.positions[::stride], 16 / 9,
                              self.take.time[::stride])
        initial = self.server.initial_camera
        initial.position, initial.look_at = tuple(camera.eye), tuple(camera.target)
        initial.up = (0.0, 1.0, 0.0)
        initial.fov = np.radians(camera.fov_degrees)

    # --- the controls -------------------------------------------------------------------------
    def _add_gui(self) -> None:
        gui, t = self.server.gui, self.timeline
        gui.add_markdown(f"**springsim play** {self.take.name}: {t.frame_count} frames, "
                         f"{t.duration:.3g} s")
        self.play_button = gui.add_button("Play")
        self.play_button.on_click(lambda _: self._toggle())
        # numbered from 1 to the frame count, as the window's label says "frame 1 of N"
        self.frame_slider = gui.add_slider("frame", 1, t.frame_count, 1, 1)
        self.frame_slider.on_update(lambda _: self._seek(self.frame_slider.value - 1))
        self.speed = gui.add_dropdown("speed", [f"{s:g}x" for s in SPEEDS], initial_value="1x")
        self.speed.on_update(lambda _: t.set_speed(SPEEDS[[f"{s:g}x" for s in SPEEDS]
                                                          .index(self.speed.value)]))
        self.loop = gui.add_checkbox("loop", t.loop)
        self.loop.on_update(lambda _: setattr(t, "loop", self.loop.value))
        self.time_text = gui.add_text("time (s)", "0", disabled=True)
        with gui.add_folder("Draw"):
            present = {SpringKind(k).label for k in set(self.model.spring_kind.tolist())}
            for name in ("surfaces", "particles", *[k.label for k in SpringKind
                                                     if k.label in present], "balls", "terrains",
                         "pins", "wind"):
                box = gui.add_checkbox(name, getattr(self.draw, name))
                box.on_update(lambda event, n=name: self.set_drawn(n, event.target.value))
        energies = recorded_energies(self.take.arrays)
        if energies:
            self._add_energy_plot(energies)

    def _add_energy_plot(self, energies: dict) -> None:
        from viser import uplot

        series = [uplot.Series(label="t (s)")] + [
            uplot.Series(label=name, stroke=color, width=2) for name, color in
            zip(energies, ("#e07020", "#3070e0", "#30a040", "#202020"))]
        # uPlot reads x as a date unless told otherwise ("1/1/70 12:00am"); the y axis is made
        # wide enough for a five-digit energy with its thousands separator ("20,000")
        with self.server.gui.add_folder("Energy (J)"):
            self.energy_plot = self.server.gui.add_uplot(
                (np.asarray(self.take.time, float), *energies.values()),
                tuple(series), aspect=1.6, scales={"x": uplot.Scale(time=False)},
                axes=(uplot.Axis(label="t (s)"), uplot.Axis(label="J", size=ENERGY_AXIS_WIDTH)))

    # --- playing ------------------------------------------------------------------------------
    def _toggle(self) -> None:
        self.timeline.toggle()
        self.play_button.label = "Pause" if self.timeline.playing else "Play"

    def _seek(self, frame: int) -> None:
        if frame != self.timeline.frame:
            self.timeline.seek(frame)
            self.show(frame)

    def set_drawn(self, name: str, shown: bool) -> None:
        setattr(self.draw, name, shown)
        for toggle, handle, update in self._parts:
            if toggle == name:
                if shown and update is not None:
                    self._drawn_time = float(self.take.time[self.timeline.frame])
                    update(self.take.positions[self.timeline.frame])
                handle.visible = shown

    def show(self, frame: int) -> None:
        """Send the positions of ``frame`` to the browser (for the parts shown)."""
        positions = self.take.positions[frame]
        self._drawn_time = float(self.take.time[frame])   # the moving terrains' (_terrain_update)
        with self.server.atomic():
            for toggle, handle, update in self._parts:
                if update is not None and getattr(self.draw, toggle):
                    update(positions)
            self.time_text.value = f"{self.take.time[frame]:.3f}"
            if self.frame_slider.value != frame + 1:
                self.frame_slider.value = frame + 1
        self._shown_frame = frame

    def tick(self) -> None:
        frame = self.timeline.advance()
        if frame != self._shown_frame:
            self.show(frame)
        self.play_button.label = "Pause" if self.timeline.playing else "Play"

    def start(self) -> "WebReplay":
        """Play in a background thread (for Jupyter); ``stop()`` ends it and the server."""
        self.timeline.play()
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()
        return self

    def _loop(self, seconds: float | None = None) -> None:
        ends = None if seconds is None else clock.perf_counter() + seconds
        while not self._stop.is_set() and (ends is None or clock.perf_counter() < ends):
            self.tick()
            clock.sleep(TICK)

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5)
        self.server.stop()


def serve(take, *, host: str, port: int, speed: float = 1.0, loop: bool = True,
          playing: bool = True, seconds: float | None = None) -> int:
    """`springsim play --web`: serve until Ctrl-C (or for ``seconds``)."""
    replay = WebReplay(take, host=host, port=port, speed=speed, loop=loop)
    if playing:
        replay.timeline.play()
    print(f"springsim play: {take.name} at {replay.url} (Ctrl-C stops)", flush=True)
    try:
        replay._loop(seconds)
    finally:
        replay.stop()
    return 0
