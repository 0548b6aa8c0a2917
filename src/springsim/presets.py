"""The built-in scenes, with the course framework's defaults."""
from pathlib import Path

import numpy as np

from .bodies.balls import Ball, Balls
from .bodies.cloth import Cloth
from .bodies.cube import Cube
from .bodies.mesh import MeshBody
from .errors import SceneError
from .scene import Scene
from .terrains import Bowl, MeshTerrain, Plane, Sphere, tilted_plane

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
}


def preset_names() -> list[str]:
    return list(PRESETS)


def preset(name: str) -> Scene:
    """A fresh copy of a built-in scene."""
    if name not in PRESETS:
        raise SceneError("scene", name, "must be a scene file or one of " + ", ".join(PRESETS))
    return PRESETS[name][0]()
