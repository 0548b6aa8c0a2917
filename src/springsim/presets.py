"""The built-in scenes, with the course framework's defaults."""
from pathlib import Path

import numpy as np

from .bodies.balls import Ball, Balls
from .bodies.cloth import Cloth
from .bodies.cube import Cube
from .animation import Animation
from .bodies.cloth_material import ClothMaterial
from .bodies.mesh import MeshBody
from .bodies.pins import Pin, Region
from .errors import SceneError
from .scene import Scene
from .motion import Keyframe, Motion
from .terrains import Bowl, MeshTerrain, Plane, Sphere, tilted_plane
from .walking_figure import FPS as FIGURE_FPS
from .wind import Gusts, Wind
from .walking_figure import NECK, NECK_HALF_WIDTH, figure_files

# meshes made by scripts/make_meshes.py (trimesh.creation), shipped with the package
MESHES = Path(__file__).resolve().parent / "meshes"


def jelly(name: str, terrain) -> Scene:
    return Scene(name=name, bodies=[Cube()], terrains=[terrain])


def cloth_balls() -> Scene:
    """The reference's scene 2 exactly: a 25 x 25 cloth, 4 x 4 m at y = 0 with its corners pinned,
    and four 125 kg balls of radius 0.5 m dropped from rest at (+-0.75, 1, +-0.75). No terrain."""
    return Scene(name="cloth-balls", bodies=[Cloth(), Balls()], terrains=[], dt=1e-4)


def cloth_hang() -> Scene:
    """The reference cloth pinned along its +z edge, starting flat 4 m up: it swings down and
    hangs (the plane at y = -1 stays below its lowest reach)."""
    return Scene(name="cloth-hang", bodies=[Cloth(position=(0.0, 4.0, 0.0), pinned="edge")],
                 terrains=[Plane()], dt=1e-4)


def jelly_balls() -> Scene:
    """The default jelly cube on the plane, with three 20 kg balls dropped on its top face."""
    balls = [Ball(position=(x, 13.0 + h, z), radius=0.5, mass=20.0)
             for x, z, h in ((-1.0, -1.0, 0.0), (0.8, -0.5, 1.0), (-0.2, 0.9, 2.0))]
    return Scene(name="jelly-balls", bodies=[Cube(), Balls(balls=balls)], terrains=[Plane()])


def ball_rain_on_cloth(particles_per_edge: int = 100, balls_per_edge: int = 10) -> Scene:
    """A large version of cloth-balls for benchmarks: a 10 x 10 m cloth with its corners pinned
    and ``balls_per_edge``^2 balls of radius 0.4 m (64 kg) in a grid 1 m above it."""
    spacing = 10.0 / balls_per_edge
    centres = (np.arange(balls_per_edge) + 0.5) * spacing - 5.0
    balls = [Ball(position=(float(x), 1.0, float(z)), radius=0.4, mass=64.0)
             for x in centres for z in centres]
    cloth = Cloth(particles_per_edge=particles_per_edge, width=10.0, height=10.0)
    return Scene(name="cloth-balls-100", bodies=[cloth, Balls(balls=balls)], terrains=[],
                 dt=1e-4)


def jelly_torus() -> Scene:
    """A jelly torus (major radius 1 m, tube radius 0.4 m, 0.2 m lattice) thrown tilted onto the
    top of a flight of stairs (an open mesh: treads and risers); it lands, hops down a step and
    settles."""
    torus = MeshBody(file=str(MESHES / "torus.obj"), spacing=0.2, rotation_degrees=75.0,
                     rotation_axis=(1.0, 0.0, 0.0), position=(1.2, 4.2, 0.0),
                     velocity=(3.0, 0.0, 0.0))
    stairs = MeshTerrain(file=str(MESHES / "stairs.obj"))
    return Scene(name="jelly-torus", bodies=[torus], terrains=[stairs], duration=6.0)


def jelly_stack() -> Scene:
    """Three default jelly cubes dropped onto each other on the plane, each a little off the
    one below: they land, squash and pile up (surface contact, collision/pipeline.py)."""
    cubes = [Cube(position=(0.0, 1.3, 0.0)), Cube(position=(0.3, 6.0, 0.2)),
             Cube(position=(-0.2, 10.7, -0.3))]
    return Scene(name="jelly-stack", bodies=cubes, terrains=[Plane()], duration=6.0)


def cloth_drape() -> Scene:
    """A free 25 x 25 cloth, 4 x 4 m, dropped flat 0.6 m above a jelly cube resting on the
    plane: it drapes over the cube, slides off its sides and folds onto itself on the floor
    (self-collision)."""
    cube = Cube(particles_per_edge=5, edge_length=1.6, position=(0.0, -0.2, 0.0),
                particle_mass=2.0)
    cloth = Cloth(position=(0.2, 1.2, 0.1), pinned="none")
    return Scene(name="cloth-drape", bodies=[cube, cloth], terrains=[Plane()], dt=1e-4,
                 duration=4.0)


def micrometres(length: float) -> float:
    """A length made by a float sum, to the micrometre, so that a printed scene says 2.19 where
    the sum left 2.1900000000000004 (`springsim scenes`)."""
    return round(length, 6)


def hanging_sheet(particles: int, width: float, height: float, top: float, pins_at: str,
                  **place) -> Cloth:
    """A cloth hanging in the plane z = 0 (turned up from the grid's xz plane) with a light
    cotton-like material, pinned along its top edge ("top") or its -x edge ("side")."""
    cloth = Cloth(particles_per_edge=particles, width=width, height=height, pinned="none",
                  rotation_degrees=90.0, rotation_axis=(1.0, 0.0, 0.0),
                  material=ClothMaterial(density=0.2), **place)
    x, y = cloth.position[0], cloth.position[1]
    edge = (Region(min=(-10.0, micrometres(top - 0.01), -0.1),
                   max=(10.0, micrometres(top + 0.01), 0.1)) if pins_at == "top"
            else Region(min=(micrometres(x - width / 2 - 0.01), micrometres(y - height), -0.1),
                        max=(micrometres(x - width / 2 + 0.01), micrometres(y + height), 0.1)))
    cloth.pins = [Pin(region=edge)]
    return cloth


def flag() -> Scene:
    """A 1.5 x 1 m flag (25 x 25) held along its -x edge, in a 6 m/s wind with gusts."""
    cloth = hanging_sheet(25, 1.5, 1.0, 2.5, "side", position=(0.75, 2.0, 0.0))
    wind = Wind(velocity=(6.0, 0.0, 0.0), friction=0.02, gusts=Gusts(0.3, 1.0, 1))
    return Scene(name="flag", bodies=[cloth], terrains=[Plane(point=(0.0, 0.0, 0.0))], wind=wind,
                 integrator="implicit_euler", dt=1 / 60, duration=6.0)


def cloth_sweep() -> Scene:
    """A 2 x 2 m curtain (25 x 25) hanging from its top edge, struck by a sphere of radius
    0.3 m that passes through it at 5 m/s."""
    cloth = hanging_sheet(25, 2.0, 2.0, 2.2, "top", position=(0.0, 1.2, 0.0))
    sweep = Motion(keyframes=[Keyframe(time=0.3), Keyframe(time=0.9, position=(0.0, 0.0, 3.0))])
    ball = Sphere(center=(0.0, 1.0, -1.5), radius=0.3, restitution=0.0, motion=sweep)
    return Scene(name="cloth-sweep", bodies=[cloth],
                 terrains=[Plane(point=(0.0, 0.0, 0.0)), ball],
                 integrator="implicit_euler", dt=1 / 60, duration=3.0)


def jelly_conveyor() -> Scene:
    """Three jelly cubes riding a 4 x 2 m platform that moves at 0.4 m/s and turns at
    0.25 rad/s about its middle: static friction carries them along."""
    cubes = [Cube(particles_per_edge=4, edge_length=0.5, position=(x, 0.4, 0.0))
             for x in (-1.2, 0.0, 1.2)]
    platform = MeshTerrain(file=str(MESHES / "platform.obj"), friction=0.8, restitution=0.2,
                           motion=Motion(velocity=(0.4, 0.0, 0.0),
                                         angular_velocity=(0.0, 0.25, 0.0)))
    return Scene(name="jelly-conveyor", bodies=cubes,
                 terrains=[platform, Plane(point=(0.0, -2.0, 0.0))],
                 integrator="implicit_euler", dt=1 / 60, duration=6.0)


def cape() -> Scene:
    """A cape (a 50 x 50 cloth, 0.5 x 0.8 m) laid flat over the shoulders of a figure that walks
    a turning path swinging its arms and legs (walking_figure.py: a mesh terrain of about 10,000
    triangles that a point cache deforms), its front edge pinned at the neck and riveted to the
    figure (follow, rivets.py): it falls over the shoulders and down the back, and rides on
    them as the figure walks and turns; implicit_euler at 1/60 s."""
    files = figure_files()
    figure = MeshTerrain(file=str(files.mesh), friction=0.4, restitution=0.0,
                         animation=Animation(str(files.cache), fps=FIGURE_FPS))
    y = micrometres(float(NECK[1]) + 0.01)   # a centimetre over the top of the figure's body
    neck = Pin(region=Region(min=(-NECK_HALF_WIDTH, micrometres(y - 0.005), NECK[2] - 0.006),
                             max=(NECK_HALF_WIDTH, micrometres(y + 0.005), NECK[2] + 0.006)),
               follow="terrains.1")
    # a fabric that bends softly (the default sheet's 50 N/m holds a cape out like a board),
    # and no drag: the reference cloth's 3.4e-4 N s/m a particle would hold these 48 mg
    # particles to 1.4 m/s, and the cape would trail the walking figure as if in a wind
    cloth = Cloth(particles_per_edge=50, width=0.5, height=0.8, pinned="none",
                  position=(0.0, y, NECK[2] - 0.4), material=ClothMaterial(bend=2.0), drag=0.0,
                  pins=[neck])
    return Scene(name="cape", bodies=[cloth], terrains=[Plane(point=(0.0, 0.0, 0.0)), figure],
                 integrator="implicit_euler", dt=1 / 60, duration=6.0)


PRESETS = {
    "jelly-plane": (lambda: jelly("jelly-plane", Plane()),
                    "the 10^3 jelly cube dropped on the plane y = -1"),
    "jelly-tilted": (lambda: jelly("jelly-tilted", tilted_plane()),
                     "the cube on a 45-degree plane through the origin (friction 0.3: it slides)"),
    "jelly-sphere": (lambda: jelly("jelly-sphere", Sphere()),
                     "the cube dropped on a sphere of radius 3 centred at (0, -1, 0)"),
    "jelly-bowl": (lambda: jelly("jelly-bowl", Bowl()),
                   "the cube inside a bowl of radius 7 centred at (2, 7, 1)"),
    "jelly-balls": (jelly_balls, "three balls dropped on the jelly cube on the plane"),
    "cloth-balls": (cloth_balls, "the reference cloth (25 x 25, corners pinned) catching four "
                                 "balls; dt 1e-4"),
    "cloth-hang": (cloth_hang, "the cloth pinned along one edge, swinging down from flat"),
    "jelly-torus": (jelly_torus, "a jelly torus (a mesh body) dropped on mesh stairs"),
    "jelly-stack": (jelly_stack, "three jelly cubes dropped onto each other: they pile up"),
    "cloth-drape": (cloth_drape, "a cloth falls over a jelly cube and folds onto itself on the "
                                 "floor; dt 1e-4"),
    "cloth-balls-100": (ball_rain_on_cloth, "benchmark: 100 balls falling on a 100 x 100 cloth"),
    "flag": (flag, "a flag held along one edge in a gusty 6 m/s wind"),
    "cloth-sweep": (cloth_sweep, "a hanging curtain struck by a sphere passing at 5 m/s"),
    "jelly-conveyor": (jelly_conveyor, "jelly cubes riding a moving, turning platform"),
    "cape": (cape, "a cape over the shoulders of a walking, turning figure (a mesh collider "
                   "that a point cache deforms), pinned at its neck"),
}


def preset_names() -> list[str]:
    return list(PRESETS)


def preset(name: str) -> Scene:
    """A fresh copy of a built-in scene."""
    if name not in PRESETS:
        raise SceneError("scene", name, "must be a scene file or one of " + ", ".join(PRESETS))
    return PRESETS[name][0]()
