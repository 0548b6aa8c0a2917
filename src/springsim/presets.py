"""The built-in scenes, with the course framework's defaults."""
from .bodies.cube import Cube
from .errors import SceneError
from .scene import Scene
from .terrains import Bowl, Plane, Sphere, tilted_plane


def jelly(name: str, terrain) -> Scene:
    return Scene(name=name, bodies=[Cube()], terrains=[terrain])


PRESETS = {
    "jelly-plane": (lambda: jelly("jelly-plane", Plane()),
                    "the 10^3 jelly cube dropped on the plane y = -1"),
    "jelly-tilted": (lambda: jelly("jelly-tilted", tilted_plane()),
                     "the cube on a 45-degree plane through the origin (friction 0.3: it slides)"),
    "jelly-sphere": (lambda: jelly("jelly-sphere", Sphere()),
                     "the cube dropped on a sphere of radius 3 centred at (0, -1, 0)"),
    "jelly-bowl": (lambda: jelly("jelly-bowl", Bowl()),
                   "the cube inside a bowl of radius 7 centred at (2, 7, 1)"),
}


def preset_names() -> list[str]:
    return list(PRESETS)


def preset(name: str) -> Scene:
    """A fresh copy of a built-in scene."""
    if name not in PRESETS:
        raise SceneError("scene", name, "must be a scene file or one of " + ", ".join(PRESETS))
    return PRESETS[name][0]()
