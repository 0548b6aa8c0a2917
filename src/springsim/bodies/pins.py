"""Pins: which particles of a body are held, chosen by number, by a box, or by a named group,
and where they are held: still, moved by a ``motion`` table, or following a moving terrain.

A body's ``pins`` is a list of ``[[bodies.pins]]`` tables, each choosing particles in one way:

- ``particles = [0, 24]``: particle numbers (for a mesh cloth, the welded vertices in the order
  they first appear in the file: the file's own numbers where it has no seams);
- ``region = {min = [...], max = [...]}``: every particle inside the box (m, scene coordinates,
  where the particle starts; the faces count as inside);
- ``group = "name"``: the vertices of a named group of the body's mesh file (an OBJ ``g`` or
  ``o`` name: Blender's OBJ exporter writes a vertex group as ``g`` lines with *Vertex Groups*
  ticked).

A pin that chooses no particle is an error: it is a mistake in the scene, not a choice.

Where the chosen particles go:

- neither ``motion`` nor ``follow``: they hold still where they start;
- ``motion``: a table like a terrain's (motion.py): each particle keeps its place in the moving
  frame, x(t) = pivot + position(t) + R(t) (x_start - pivot), the pivot defaulting to the mean of
  the chosen particles' starting positions;
- ``follow = "terrains.N"``: the particles keep their place in terrain N's moving frame (its own
  motion, about its own pivot); a terrain that does not move holds them still; on a deforming
  terrain each is riveted to the triangle nearest to it (rivets.py);
- ``animation``: a point cache (animation.py) of the body's own points, as an animated copy of
  it in Blender or Houdini writes it: each chosen particle goes where its point goes. The cache
  lists a mesh cloth's file vertices (file order, the file's frame: placed as the cloth is), or
  the particles of a grid cloth or a cube (scene coordinates).

A pin is hard by default: the particle is exactly on its path at the end of every step, under
every integrator (world.py), and moves with the path's velocity. With ``stiffness`` (N/m) it is
soft: a spring from the particle to its path's point, with ``damping`` (N s/m) against the
velocity relative to the path.
"""
import re
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from ..animation import Animation
from ..errors import SceneError, is_finite, require
from ..motion import Motion, Path

FOLLOW = re.compile(r"terrains\.(0|[1-9][0-9]*)")


@dataclass
class Region:
    """An axis-aligned box: ``min`` and ``max`` corners (m)."""

    min: tuple = (0.0, 0.0, 0.0)
    max: tuple = (0.0, 0.0, 0.0)


@dataclass
class Pin:
    """One way of choosing pinned particles: exactly one of ``particles``, ``region``, ``group``."""

    particles: list = field(default_factory=list)   # particle numbers
    region: Region | None = None                    # a box at the start (m)
    group: str = ""                                 # a named group of the mesh file
    motion: Motion | None = None                    # moves the chosen particles (motion.py)
    follow: str = ""                                # "terrains.N": moves them with terrain N
    stiffness: float | None = None                  # N/m: a soft pin (a spring); unset: hard
    damping: float = 0.0                            # N s/m, a soft pin's damper
    animation: Animation | None = None              # a point cache of the body's points

    def validate(self, key: str) -> None:
        if self.stiffness is not None:
            require(is_finite(self.stiffness) and self.stiffness > 0, f"{key}.stiffness",
                    self.stiffness, "must be > 0 N/m (leave it out for a hard pin)")
        require(is_finite(self.damping) and self.damping >= 0, f"{key}.damping", self.damping,
                "must be >= 0 N s/m")
        if self.motion is not None:
            self.motion.validate(f"{key}.motion")
        if self.animation is not None:
            require(self.motion is None and not self.follow, f"{key}.animation",
                    self.animation.file, "a pin has one of motion, follow and animation")
            self.animation.validate(f"{key}.animation")
        if self.follow:
            require(FOLLOW.fullmatch(self.follow) is not None, f"{key}.follow", self.follow,
                    'must name a terrain as "terrains.N" (N its number, from 0)')
            require(self.motion is None, f"{key}.follow", self.follow,
                    "a pin follows a terrain or has its own motion, not both")
        check_choice(self, key, "a pin", ("particles", "region", "group"))


def check_choice(choice, key: str, what: str, ways: tuple) -> None:
    """``choice`` (a Pin, or anything with its ``particles``, ``region`` and ``group``) chooses
    its particles in exactly one of ``ways``, and a region is a box. Shared by pins and
    attachments (attachments.py), so that both choose particles alike."""
    given = [name for name in ways if getattr(choice, name)]
    spelled = {"particles": "particles = [...]", "region": "region = {min = [...], max = [...]}",
               "group": 'group = "name"'}
    listed = [spelled[name] for name in ways]
    require(len(given) == 1, key, given or "nothing",
            f"{what} chooses its particles in exactly one way: " + ", ".join(listed[:-1])
            + f" or {listed[-1]}")
    if choice.region is not None:
        low, high = choice.region.min, choice.region.max
        for name, corner in (("min", low), ("max", high)):
            require(np.shape(corner) == (3,) and is_finite(corner), f"{key}.region.{name}",
                    corner, "must be three finite numbers (m)")
        require(bool(np.all(np.asarray(low) <= np.asarray(high))), f"{key}.region",
                {"min": low, "max": high}, "needs min <= max on every axis")


def pinned_mask(pins, positions: np.ndarray, groups: dict, key: str) -> np.ndarray:
    """(n,) bool: the particles that ``pins`` choose, at ``positions`` (n, 3); ``groups`` maps a
    group name to its particle numbers. Every pin must choose at least one particle."""
    mask = np.zeros(len(positions), bool)
    for p, pin in enumerate(pins):
        chosen = chosen_particles(pin, positions, groups, f"{key}.{p}")
        require(chosen.size > 0, f"{key}.{p}", describe(pin), "chooses no particle; "
                + start_hint(positions))
        if pin.stiffness is None:   # a soft pin's particles keep their mass: a spring holds them
            mask[chosen] = True
    return mask


def chosen_particles(pin: Pin, positions: np.ndarray, groups: dict, key: str) -> np.ndarray:
    count = len(positions)
    if pin.particles:
        for index in pin.particles:
            whole = isinstance(index, (int, np.integer)) and not isinstance(index, bool)
            require(whole and 0 <= index < count, f"{key}.particles", index,
                    f"particle numbers must be whole numbers in [0, {count - 1}]")
        return np.unique(np.asarray(pin.particles, np.int64))
    if pin.region is not None:
        low, high = np.asarray(pin.region.min, float), np.asarray(pin.region.max, float)
        inside = np.all((positions >= low) & (positions <= high), axis=1)
        return np.flatnonzero(inside)
    if pin.group not in groups:
        raise SceneError(f"{key}.group", pin.group,
                         "names no group of the mesh file; it has " + (
                             ", ".join(sorted(groups)) if groups else "none (only OBJ files "
                             "carry groups: g or o lines)"))
    return np.asarray(groups[pin.group], np.int64)


def followed_terrain(pin: Pin) -> int:
    """The number of the terrain a pin follows, or -1."""
    return int(FOLLOW.fullmatch(pin.follow).group(1)) if pin.follow else -1


def check_follows(pins, terrains, key: str) -> None:
    """Every ``follow`` names a terrain of the scene (its particles keep their place in a rigid
    terrain's frame, or riveted to a deforming one's nearest triangles: rivets.py)."""
    terrain_count = len(terrains)
    for p, pin in enumerate(pins):
        if pin.follow:
            require(followed_terrain(pin) < terrain_count, f"{key}.{p}.follow", pin.follow,
                    f"names no terrain: the scene has {terrain_count} "
                    f"(terrains.0 to terrains.{terrain_count - 1})" if terrain_count else
                    "names no terrain: the scene has none")


def particle_cache(count: int):
    """``cache_points`` for a body whose cache lists its ``count`` particles as they are."""
    def cache_points(points: np.ndarray, key: str, file: str) -> np.ndarray:
        require(points.shape[1] == count, f"{key}.file", file,
                f"moves {points.shape[1]} points, but the body has {count} particles")
        return points
    return cache_points


class MovingPin(NamedTuple):
    """A pin that moves or is soft: its particles, its table, and its particles' paths (a
    Path each) where it has an animation."""

    particles: np.ndarray
    pin: Pin
    paths: list | None = None


def moving_pins(pins, positions: np.ndarray, groups: dict, cache_points=None,
                key: str = "pins") -> list:
    """A MovingPin for each pin that moves (a motion, a followed terrain or an animation) or
    is soft (a spring to where it starts). ``cache_points(cache, key, file)`` places an
    animation's samples (F, V, 3) as the body's particles (F, P, 3); a body without it takes
    none. A body's ``validate`` calls it with its own ``key`` (``bodies.N.pins``), so that a
    cache that does not fit the body is refused by its full key before anything is built."""
    moving = []
    for p, pin in enumerate(pins):
        if pin.motion is None and not pin.follow and pin.stiffness is None and \
                pin.animation is None:
            continue
        chosen = chosen_particles(pin, positions, groups, f"{key}.{p}")
        paths = None
        if pin.animation is not None:
            here = f"{key}.{p}.animation"
            require(cache_points is not None, here, pin.animation.file,
                    "moves the particles of a cloth or a cube; a mesh body's particles are "
                    "not its file's vertices (pin them with a motion or follow instead)")
            cache = pin.animation.cache(f"{here}.file")
            placed = cache_points(cache.points, here, pin.animation.file)[:, chosen]
            paths = [Path(times=cache.times, displacements=placed[:, j] - positions[i])
                     for j, i in enumerate(chosen)]
        moving.append(MovingPin(chosen, pin, paths))
    return moving


def describe(pin: Pin):
    """A choice (a Pin's or an attachment's) as the scene file says it, for an error."""
    if pin.region is not None:
        return {"region": {"min": list(pin.region.min), "max": list(pin.region.max)}}
    return {"particles": pin.particles} if pin.particles else {"group": pin.group}


def start_hint(positions: np.ndarray) -> str:
    """Where a body's particles start, for an error about a choice that chose none."""
    low, high = positions.min(axis=0), positions.max(axis=0)
    return (f"the body's particles start within min = {np.round(low, 4).tolist()}, "
            f"max = {np.round(high, 4).tolist()}")


def pinned_particles(model) -> np.ndarray:
    """The particles a pin holds (no inverse mass) or moves (``pin_particles``), numbered."""
    mask = np.array(getattr(model, "pinned", np.zeros(model.particle_count, bool)), bool)
    mask[np.asarray(getattr(model.arrays, "pin_particles", np.zeros(0, np.int64)), np.int64)] = True
    return np.flatnonzero(mask).astype(np.int64)
