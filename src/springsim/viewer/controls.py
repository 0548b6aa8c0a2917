"""What each control of the viewer's panel does to the simulation, as plain Python.

The panel (panel.py) only reads these values and calls these methods, so that a test can drive
every control with no window. A setting that changes the physics edits a copy of the scene's
dataclasses and rebuilds the Simulation from it (cheap); the rebuild keeps the current state when
the particles stay the same (stiffness, damping, restitution, friction, drag, integrator, dt, a
body's thickness and self-collision), and starts over when they do not (scene, terrain, cube
height and rotation, particles per edge). A setting that cannot be simulated leaves everything as
it was and shows why in ``message``.

In the window (``compile_in_background``), a step whose kernel is not compiled for this
simulation (a new integrator, the threaded kernel of a large model: warmup.py) compiles on a
thread, for minutes on two cores, while the window stays live and ``message`` says so with the
seconds (compile_notice.py); the steps wait for it.
"""
import copy
import dataclasses
import sys
import threading
import time

import numpy as np

from ..bodies.cube import Cube
from ..collision.pair_lists import no_pair_list
from ..collision.shapes.settings import SurfaceContact
from ..errors import SceneError, SimulationDiverged
from ..render.drawing import DrawOptions
from ..scene import Scene
from ..scenefile import load_scene
from ..simulation import Simulation
from ..springs import SpringKind, SpringParameters
from ..terrains import TERRAIN_TYPES
from ..compile_notice import NOTICE, announced, kernels_of
from ..warmup import is_compiled
from .frame_stats import FrameStats
from .mouse_spring import MouseSpring

UNSTABLE_MESSAGE = "System Unstable! Please reset the parameters!"
COMPILING_MESSAGE = "{notice}: {seconds:.0f} s"
# The terrain buttons: every kind that names one (``menu_name``: the course framework's plane,
# tilted plane, sphere and bowl; a mesh terrain needs a file, so it has none), plus none (the
# cloth scenes have no terrain).
TERRAINS = {**{factory().menu_name(): factory for factory in TERRAIN_TYPES.values()
               if hasattr(factory(), "menu_name")}, "none": None}


class Controls:
    """The viewer's state: a scene, its simulation, the run state and the live figures."""

    def __init__(self, scene="jelly-plane", integrator: str | None = None,
                 dt: float | None = None, threads: int | None = None):
        """``scene``: a built-in scene's name, a scene file, or a Scene; ``threads``: the most
        threads a step may use (default: all cores)."""
        self.threads = threads
        self.draw = DrawOptions()
        self.mouse = MouseSpring()
        self.stats = FrameStats()
        self.running = False
        self.unstable = False
        self.message = ""
        self.version = 0       # grows with every new Simulation: the drawing must follow
        self.reframe = True    # the camera should frame the scene anew
        self.compiling = None  # the KernelCompile under way, if any
        # compile a step's kernel on a thread (the window sets it: it must stay live); without
        # it, the step compiles where it is called, said on stderr (Simulation)
        self.compile_in_background = False
        self._compiled_for = None   # the Simulation whose step kernel is known compiled
        self._load(scene, integrator, dt)

    # --- scene and terrain ----------------------------------------------------------------
    def _load(self, scene, integrator=None, dt=None) -> None:
        if isinstance(scene, Scene):
            scene, self.scene_name = copy.deepcopy(scene), scene.name
        else:
            scene, self.scene_name = load_scene(scene), str(scene)
        self._replace(Simulation(scene, integrator=integrator, dt=dt, threads=self.threads),
                      keep_state=False)
        self.steps_per_frame = real_time_steps(self.sim.dt)

    def choose_scene(self, name: str) -> bool:
        """Load a built-in scene or a scene file; it starts stopped, at its first state."""
        try:
            self._load(name)
        except SceneError as error:
            self.message = str(error)
            return False
        self.running = False
        return True

    def choose_terrain(self, name: str) -> bool:
        """Replace the terrains with one of TERRAINS (the course framework's terrain buttons)."""
        if name not in TERRAINS:
            self.message = str(SceneError("terrain", name, "must be one of " + ", ".join(TERRAINS)))
            return False
        make = TERRAINS[name]
        return self._edit(lambda scene: setattr(scene, "terrains", [make()] if make else []),
                          keep_state=False)

    def terrain_name(self) -> str:
        terrains = self.sim.scene.terrains
        if not terrains:
            return "none"
        terrain = terrains[0]
        return terrain.menu_name() if hasattr(terrain, "menu_name") else type(terrain).__name__

    # --- settings that keep the state -----------------------------------------------------
    def set_integrator(self, name: str) -> bool:
        return self._edit(lambda scene: setattr(scene, "integrator", name))

    def set_dt(self, dt: float) -> bool:
        return self._edit(lambda scene: setattr(scene, "dt", float(dt)))

    def set_steps_per_frame(self, steps: int) -> None:
        self.steps_per_frame = max(1, int(steps))

    def set_spring(self, kind: SpringKind, ks: float | None = None,
                   kd: float | None = None) -> bool:
        """Stiffness ks (N/m) and damping kd (N s/m) of one kind of spring, in every body."""
        def edit(scene):
            for body in scene.bodies:
                params = getattr(body, SpringKind(kind).label, None)
                if isinstance(params, SpringParameters):
                    changes = {k: float(v) for k, v in (("ks", ks), ("kd", kd)) if v is not None}
                    setattr(body, SpringKind(kind).label, dataclasses.replace(params, **changes))
        return self._edit(edit)

    def spring(self, kind: SpringKind) -> SpringParameters | None:
        """The first body's parameters of this kind, None if no body has such springs."""
        for body in self.sim.scene.bodies:
            params = getattr(body, SpringKind(kind).label, None)
            if isinstance(params, SpringParameters):
                return params
        return None

    def has_face_springs(self) -> bool:
        return any(getattr(body, "face_springs", False) for body in self.sim.scene.bodies)

    def set_restitution(self, value: float) -> bool:
        return self._edit_terrains("restitution", float(value))

    def set_friction(self, value: float) -> bool:
        return self._edit_terrains("friction", float(value))

    def _edit_terrains(self, key: str, value: float) -> bool:
        def edit(scene):
            for terrain in scene.terrains:
                setattr(terrain, key, value)
        return self._edit(edit)

    def terrain_value(self, key: str) -> float | None:
        terrains = self.sim.scene.terrains
        return getattr(terrains[0], key) if terrains else None

    def set_drag(self, value: float) -> bool:
        return self._edit(lambda scene: setattr(scene, "drag", float(value)))

    def contact_bodies(self) -> list[tuple[int, str, SurfaceContact]]:
        """(number in the scene, name, settings) of every body with surface contact keys."""
        names = [body.name for body in self.sim.model.bodies]
        return [(number, names[number], body) for number, body in
                enumerate(self.sim.scene.bodies) if isinstance(body, SurfaceContact)]

    def set_thickness(self, body: int, metres: float) -> bool:
        """How far (m) body number ``body`` keeps other surfaces, and its own, away."""
        return self._edit(lambda scene: setattr(scene.bodies[body], "thickness", float(metres)))

    def set_self_collision(self, body: int, on: bool) -> bool:
        """Whether body number ``body``'s surface pushes on itself."""
        return self._edit(lambda scene: setattr(scene.bodies[body], "self_collision", bool(on)))

    # --- settings that start over ---------------------------------------------------------
    def set_cube_height(self, y: float) -> bool:
        """Height (m) of every cube's centre at the start."""
        def edit(scene):
            for cube in self._cubes(scene):
                cube.position = (cube.position[0], float(y), cube.position[2])
        return self._edit(edit, keep_state=False)

    def set_cube_rotation(self, degrees: float) -> bool:
        """Every cube's starting rotation (degrees) about its axis, (1, 0, 1) by default."""
        def edit(scene):
            for cube in self._cubes(scene):
                cube.rotation_degrees = float(degrees)
        return self._edit(edit, keep_state=False)

    def cube(self) -> Cube | None:
        cubes = self._cubes(self.sim.scene)
        return cubes[0] if cubes else None

    @staticmethod
    def _cubes(scene) -> list:
        return [body for body in scene.bodies if isinstance(body, Cube)]

    def set_particles_per_edge(self, count: int) -> bool:
        """Particles per edge of every cube and cloth (rebuilds them)."""
        def edit(scene):
            for body in scene.bodies:
                if hasattr(body, "particles_per_edge"):
                    body.particles_per_edge = int(count)
        return self._edit(edit, keep_state=False)

    def particles_per_edge(self) -> int | None:
        for body in self.sim.scene.bodies:
            if hasattr(body, "particles_per_edge"):
                return body.particles_per_edge
        return None

    # --- rebuilding -----------------------------------------------------------------------
    def _edit(self, change, keep_state: bool = True) -> bool:
        """Apply ``change`` to a copy of the scene and rebuild; on a SceneError keep the old."""
        scene = copy.deepcopy(self.sim.scene)
        change(scene)
        try:
            sim = Simulation(scene, threads=self.threads)
        except SceneError as error:
            self.message = str(error)
            return False
        self._replace(sim, keep_state)
        return True

    def _replace(self, sim: Simulation, keep_state: bool) -> None:
        old = getattr(self, "sim", None)
        if keep_state and old is not None and old.model.particle_count == sim.model.particle_count:
            # the motion goes on; the pair lists were found for the old model (its surfaces and
            # thicknesses), so the new one finds its own
            sim.state = dataclasses.replace(old.state, pairs=no_pair_list(), solve_pairs=None)
            sim.steps_taken = old.steps_taken
        else:
            self.reframe = True
            self.unstable = False
            self.mouse.release()
        self.sim = sim
        self.version += 1
        if not self.unstable:
            self.message = ""

    # --- running --------------------------------------------------------------------------
    def start(self) -> None:
        """Start from the first state (as the course framework's Start button does)."""
        self.reset()
        self.running = True

    def stop(self) -> None:
        self.running = False

    def resume(self) -> None:
        self.running = not self.unstable

    def reset(self) -> None:
        self.sim.reset()
        self.unstable = False
        self.message = ""
        self.mouse.release()
        self.stats.restart()

    def step_frame(self) -> int:
        """One frame's worth of steps while stopped (the Step button); the steps taken."""
        return 0 if self.unstable else self._advance(self.steps_per_frame)

    def advance_frame(self, now: float | None = None) -> int:
        """What happens every drawn frame: step if running, and count the figures."""
        now = time.perf_counter() if now is None else now
        start_time = self.sim.time
        steps = self._advance(self.steps_per_frame) if self.running else 0
        self.stats.frame(now, steps, self.sim.time - start_time)
        return steps

    def _advance(self, count: int) -> int:
        if not self.step_ready():
            return 0
        sim = self.sim
        before = sim.steps_taken
        try:
            if self.mouse.holding:   # one step at a time, the mouse spring's impulse before each
                for _ in range(count):
                    self.mouse.apply(sim.state, sim.model, sim.dt)
                    sim.step(1)
            else:
                sim.step(count)
        except SimulationDiverged as error:
            self.running = False
            self.unstable = True
            self.mouse.release()
            self.message = f"{UNSTABLE_MESSAGE}\n{error}"
        return sim.steps_taken - before

    def step_ready(self) -> bool:
        """Whether the simulation's step may be taken now. Where its kernel is not compiled and
        ``compile_in_background`` is set, it compiles on a thread (KernelCompile) and this is
        false until that is done; a kernel in the cache on disk loads in the step, in a second
        or two."""
        sim = self.sim
        if self._compiled_for is sim:
            return True
        done = self.compiling
        if done is not None:
            if done.thread.is_alive():
                return False
            self.compiling = None
            if self.message.startswith(done.notice):
                self.message = ""
            if done.error is not None:
                self.running = False
                self.message = f"compiling {done.what} failed: {done.error}"
                return False
        call = step_call(sim) if self.compile_in_background else None
        if call is not None and not is_compiled(call):
            self.compiling = KernelCompile(call, kernels_of(sim), self._say)
            return False
        self._compiled_for = sim
        return True

    def _say(self, line: str) -> None:
        self.message = line

    def energy(self) -> dict:
        """Kinetic, gravitational, spring and total energy (J) now."""
        return self.sim.energy()

    # --- pulling with the mouse -----------------------------------------------------------
    def grab(self, particle: int, target) -> None:
        self.mouse.grab(particle, target)

    def pull_to(self, target) -> None:
        self.mouse.move(target)

    def release(self) -> None:
        self.mouse.release()

    def held_position(self) -> np.ndarray | None:
        if not self.mouse.holding:
            return None
        return self.sim.positions[self.mouse.particle]


def step_call(sim):
    """The compiled call a step of ``sim`` makes (integrators.KernelCall), or None for a method
    that is not one compiled call."""
    kernel_call = getattr(sim.integrator, "kernel_call", None)
    if kernel_call is None:
        return None
    return kernel_call(sim.model, sim.state, sim.dt, 0)


class KernelCompile:
    """A step kernel compiling on a thread, for its arguments' types (it never runs it), said
    on stderr as the command line says it (compile_notice.announced) and, through ``say(line)``, in
    the window: the notice and the seconds so far."""

    def __init__(self, call, what: str, say):
        self.what, self.error = what, None
        self.notice = NOTICE.format(what=what)
        types = tuple(call.kernel.typeof_pyval(argument) for argument in call.arguments)
        self.thread = threading.Thread(target=self._compile, args=(call.kernel, types, say),
                                       daemon=True)
        self.thread.start()

    def _compile(self, kernel, types, say) -> None:
        def ticking(seconds):
            say(COMPILING_MESSAGE.format(notice=self.notice, seconds=seconds))

        try:
            with announced(self.what, sys.stderr, on_compile=ticking):
                kernel.compile(types)
        except Exception as error:   # shown in the window, which stays open
            self.error = error


def real_time_steps(dt: float, frames_per_second: float = 60.0) -> int:
    """Steps per drawn frame that would keep pace with the clock at 60 frames per second."""
    return max(1, int(round(1.0 / (frames_per_second * dt))))
