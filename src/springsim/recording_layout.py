"""What a recording says about its model, so that export and replay need no scene file.

``layout_arrays(model)`` gives the arrays an NPZ recording carries besides the frames, and
``read_layout(arrays)`` turns them back into a ``Layout``: the bodies (``model.BodySlice``: name,
particle range, surface triangles and, for mesh bodies, the ``surfaces.Embedding``), the balls
(particle numbers and radii) and the terrains (the scene file's own ``[[terrains]]`` tables, so
that every terrain kind the scene files know comes back as the same object).

Arrays (B bodies, T surface triangles in all, E embedded vertices in all, N balls):

| key | shape | meaning |
|---|---|---|
| ``layout_version`` | () | LAYOUT_VERSION |
| ``body_names`` | (B,) str | |
| ``body_particles`` | (B, 2) | first particle and one past the last |
| ``body_surface_rows`` | (B + 1,) | body b's triangles are rows [r_b, r_b+1) of ``body_surfaces`` |
| ``body_surfaces`` | (T, 3) | as in BodySlice.surface |
| ``body_embedded`` | (B,) bool | whether body b's surface numbers embedded vertices |
| ``body_embedding_rows`` | (B + 1,) | body b's vertices are rows [e_b, e_b+1) of the two below |
| ``embedding_particles``, ``embedding_weights`` | (E, 8) | surfaces.Embedding, stacked |
| ``ball_particles``, ``ball_radii`` | (N,) | particle numbers, m |
| ``terrains_toml`` | () str | the terrains as scene-file tables |
| ``pinned_particles`` | (H,) | the particles a pin holds or moves (drawn by replays) |
| ``wind_keys`` | (K, 4) | the wind's keys (time, velocity), none without wind (drawn by replays) |

A recording written before these arrays existed (no ``layout_version``) still reads: its one
``surface`` array (global particle numbers) becomes one body, with no balls and no terrains, and
``Layout.legacy`` says so; one written before the pins and the wind were recorded reads with
none.
"""
import tomllib
from dataclasses import dataclass, field

import numpy as np

from .errors import SceneError, require
from .bodies.pins import pinned_particles
from .model import BodySlice
from .surfaces import Embedding

LAYOUT_VERSION = 1
LAYOUT_KEYS = ("layout_version", "body_names", "body_particles", "body_surface_rows",
               "body_surfaces", "body_embedded", "body_embedding_rows", "embedding_particles",
               "embedding_weights", "ball_particles", "ball_radii", "terrains_toml",
               "pinned_particles", "wind_keys")


@dataclass(frozen=True)
class Layout:
    bodies: tuple               # model.BodySlice per body
    ball_particles: np.ndarray  # (N,) particle numbers
    ball_radii: np.ndarray      # (N,) m
    terrains: tuple             # terrain objects (terrains.Plane, ...)
    legacy: bool = False        # read from a recording that had no layout
    pinned: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))   # (H,)
    wind_keys: np.ndarray = field(default_factory=lambda: np.zeros((0, 4)))    # (K, 4)


def layout_arrays(model) -> dict:
    """The layout of ``model`` as NPZ arrays (see the module's table)."""
    bodies = model.bodies
    embeddings = [body.embedding for body in bodies if body.embedding is not None]
    balls = np.asarray(model.arrays.balls, np.int64)
    return {
        "layout_version": np.asarray(LAYOUT_VERSION),
        "body_names": np.asarray([body.name for body in bodies], dtype=str),
        "body_particles": np.asarray([(body.start, body.stop) for body in bodies],
                                     np.int64).reshape(-1, 2),
        "body_surface_rows": _row_offsets([len(body.surface) for body in bodies]),
        "body_surfaces": _stack([np.asarray(body.surface, np.int64) for body in bodies], (0, 3),
                                np.int64),
        "body_embedded": np.asarray([body.embedding is not None for body in bodies], bool),
        "body_embedding_rows": _row_offsets([len(body.embedding.particles)
                                             if body.embedding is not None else 0
                                             for body in bodies]),
        "embedding_particles": _stack([np.asarray(e.particles, np.int64) for e in embeddings],
                                      (0, 8), np.int64),
        "embedding_weights": _stack([np.asarray(e.weights, float) for e in embeddings], (0, 8),
                                    float),
        "ball_particles": balls,
        "ball_radii": np.asarray(model.arrays.radius, float)[balls],
        "terrains_toml": np.asarray(terrains_toml(model.terrains)),
        "pinned_particles": pinned_particles(model),   # bodies/pins.py
        "wind_keys": recorded_wind_keys(model),
    }


def recorded_wind_keys(model) -> np.ndarray:
    """The wind's keys (time, velocity), or none when the scene has no [wind]."""
    from .wind import ON

    settings = getattr(model.arrays, "wind_settings", None)
    if settings is None or not settings[ON]:
        return np.zeros((0, 4))
    return np.asarray(model.arrays.wind_keys, float)


def read_layout(arrays, scene_name: str = "body") -> Layout:
    """The Layout stored in ``arrays`` (an NPZ file's arrays, or ``layout_arrays``' dict)."""
    if "layout_version" not in arrays:
        return legacy_layout(arrays, scene_name)
    version = int(arrays["layout_version"])
    require(version <= LAYOUT_VERSION, "layout_version", version,
            f"this springsim reads recordings up to layout version {LAYOUT_VERSION}; "
            "update springsim")
    surface_rows, embedding_rows = arrays["body_surface_rows"], arrays["body_embedding_rows"]
    particles, weights = arrays["embedding_particles"], arrays["embedding_weights"]
    bodies = []
    for b, (name, (start, stop)) in enumerate(zip(arrays["body_names"], arrays["body_particles"])):
        embedding = None
        if arrays["body_embedded"][b]:
            rows = slice(int(embedding_rows[b]), int(embedding_rows[b + 1]))
            embedding = Embedding(particles[rows], weights[rows])
        surface = arrays["body_surfaces"][int(surface_rows[b]):int(surface_rows[b + 1])]
        bodies.append(BodySlice(str(name), int(start), int(stop), surface, embedding))
    pinned = arrays["pinned_particles"] if "pinned_particles" in arrays else np.zeros(0)
    wind_keys = arrays["wind_keys"] if "wind_keys" in arrays else np.zeros((0, 4))
    return Layout(tuple(bodies), np.asarray(arrays["ball_particles"], np.int64),
                  np.asarray(arrays["ball_radii"], float),
                  read_terrains(str(arrays["terrains_toml"])),
                  pinned=np.asarray(pinned, np.int64),
                  wind_keys=np.asarray(wind_keys, float).reshape(-1, 4))


def legacy_layout(arrays, scene_name: str) -> Layout:
    """A recording from before layouts: its surface as one body over all particles."""
    require("surface" in arrays and "positions" in arrays, "recording", sorted(arrays)[:6],
            "is not a springsim recording (no positions and surface arrays)")
    particles = np.shape(arrays["positions"])[1]
    body = BodySlice(scene_name, 0, particles, np.asarray(arrays["surface"], np.int64))
    return Layout((body,), np.empty(0, np.int64), np.empty(0), (), legacy=True)


def terrains_toml(terrains) -> str:
    """The terrains as the ``[[terrains]]`` tables of a scene file."""
    from .scene import Scene
    from .scenefile import scene_to_toml

    return scene_to_toml(Scene(name="terrains", terrains=list(terrains)))


def read_terrains(text: str) -> tuple:
    from .scene import Scene
    from .scenefile import merge_table

    try:
        table = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise SceneError("terrains_toml", text[:40], f"is not valid TOML: {error}") from None
    return tuple(merge_table(Scene(), {"terrains": table.get("terrains", [])}, "").terrains)


def _row_offsets(counts) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(counts, dtype=np.int64)]).astype(np.int64)


def _stack(parts, empty_shape, dtype) -> np.ndarray:
    return np.concatenate(parts).astype(dtype) if parts else np.empty(empty_shape, dtype)
