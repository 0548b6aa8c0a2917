"""Pins: which particles of a body hold still, chosen by number, by a box, or by a named group.

A body's ``pins`` is a list of ``[[bodies.pins]]`` tables, each choosing particles in one way:

- ``particles = [0, 24]``: particle numbers (for a mesh cloth, the welded vertices in the order
  they first appear in the file: the file's own numbers where it has no seams);
- ``region = {min = [...], max = [...]}``: every particle inside the box (m, scene coordinates,
  where the particle starts; the faces count as inside);
- ``group = "name"``: the vertices of a named group of the body's mesh file (an OBJ ``g`` or
  ``o`` name: Blender's OBJ exporter writes a vertex group as ``g`` lines with *Vertex Groups*
  ticked).

A pin that chooses no particle is an error: it is a mistake in the scene, not a choice.
"""
from dataclasses import dataclass, field

import numpy as np

from ..errors import SceneError, is_finite, require


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

    def validate(self, key: str) -> None:
        given = [name for name in ("particles", "region", "group") if getattr(self, name)]
        require(len(given) == 1, key, given or "nothing",
                "a pin chooses its particles in exactly one way: particles = [...], "
                "region = {min = [...], max = [...]} or group = \"name\"")
        if self.region is not None:
            low, high = self.region.min, self.region.max
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
                + _hint(pin, positions))
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


def describe(pin: Pin):
    if pin.region is not None:
        return {"region": {"min": list(pin.region.min), "max": list(pin.region.max)}}
    return {"particles": pin.particles} if pin.particles else {"group": pin.group}


def _hint(pin: Pin, positions: np.ndarray) -> str:
    low, high = positions.min(axis=0), positions.max(axis=0)
    return (f"the body's particles start within min = {np.round(low, 4).tolist()}, "
            f"max = {np.round(high, 4).tolist()}")
