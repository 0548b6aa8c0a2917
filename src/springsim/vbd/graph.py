"""Each particle's springs, and a colouring of the particles that no spring joins within a colour.

Vertex block descent updates one particle at a time from its neighbours' latest positions. The
particles of one colour share no spring, so each reads only particles of other colours, and a
colour's particles can be updated in any order, on any number of threads, with the same bits:
the colouring fixes the result, and it is computed once per model (``vertex_graph``), greedily in
particle order, so that the same model always gets the same colours.

A particle's springs are laid out contiguously, each entry with what the block needs of the
spring (the other end, rest length, ks, kd) beside it, and the particles' entries one after
another in the order a sweep visits the particles (by colour), so that a sweep reads them
in one pass through memory instead of through the spring tables (a 100 x 100 cloth's entries
are 4 MB, more than the caches hold).
"""
from typing import NamedTuple

import numpy as np

from .._jit import kernel


class VertexGraph(NamedTuple):
    """The springs of each particle, and the particles by colour (module doc)."""

    start: np.ndarray            # (F + 1,) int64: particles[n]'s entries are start[n]:start[n + 1]
    other: np.ndarray            # (E,) int64: the spring's other end
    rest_length: np.ndarray      # (E,) m
    ks: np.ndarray               # (E,) N/m
    kd: np.ndarray               # (E,) N s/m
    colour_start: np.ndarray     # (C + 1,) int64: colour c is particles[colour_start[c]:...[c + 1]]
    particles: np.ndarray        # (F,) int64: the free particles (inverse mass > 0), by colour


def vertex_graph(arrays) -> VertexGraph:
    """The graph of a model's ModelArrays (module doc)."""
    count = arrays.inv_mass.shape[0]
    springs = arrays.springs.astype(np.int64)
    ends = np.concatenate([springs[:, 0], springs[:, 1]])
    others = np.concatenate([springs[:, 1], springs[:, 0]])
    number = np.concatenate([np.arange(len(springs))] * 2)
    order = np.argsort(ends, kind="stable")   # by particle, each one's springs in spring order
    start = np.searchsorted(ends[order], np.arange(count + 1)).astype(np.int64)
    number = number[order]
    group = arrays.spring_group[number]
    other = np.ascontiguousarray(others[order])
    colour = greedy_colours(start, other, count)
    free = np.flatnonzero(arrays.inv_mass > 0.0)
    by_colour = free[np.argsort(colour[free], kind="stable")]
    colour_start = np.searchsorted(colour[by_colour], np.arange(colour.max(initial=-1) + 2))
    # the free particles' entries in sweep order (module doc)
    counts = start[by_colour + 1] - start[by_colour]
    entries = np.repeat(start[by_colour] - np.cumsum(counts) + counts, counts) + np.arange(
        counts.sum())
    return VertexGraph(np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
                       np.ascontiguousarray(other[entries]),
                       np.ascontiguousarray(arrays.rest_length[number][entries]),
                       np.ascontiguousarray(arrays.group_ks[group][entries]),
                       np.ascontiguousarray(arrays.group_kd[group][entries]),
                       colour_start.astype(np.int64), by_colour.astype(np.int64))


@kernel
def greedy_colours(start, other, count):
    """Each particle the least colour none of its earlier-coloured neighbours has, in particle
    order."""
    colour = np.full(count, -1, np.int64)
    most = 1
    for i in range(count):
        most = max(most, start[i + 1] - start[i] + 1)
    taken = np.full(most + 1, -1, np.int64)   # taken[c] == i: a neighbour of i has colour c
    for i in range(count):
        for k in range(start[i], start[i + 1]):
            c = colour[other[k]]
            if c >= 0:
                taken[c] = i
        c = 0
        while taken[c] == i:
            c += 1
        colour[i] = c
    return colour
