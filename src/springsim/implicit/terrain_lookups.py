"""How backward Euler's constraints see the terrains (implicit/constraints.py): the terrain a
particle reaches first in a step, from each terrain's (phi, normal) at its start; and, beyond a
deforming mesh's reach, where its lookup answers infinity, the lookups along the step's path
instead."""
import math

import numpy as np

from .._jit import inline_kernel
from ..world import terrain_at

MAX_SWEEP_POINTS = 64    # the most points of a step's path a swept lookup asks (swept_lookup)


@inline_kernel
def closest_terrain(epsilon, lookups, row, u0, u1, u2, h, in_reach):
    """The terrain that a particle moving at (u0, u1, u2) reaches first this step, with phi, the
    normal and the normal velocity; terrain -1 if it reaches none. Each terrain's phi and normal
    at the particle are ``lookups[row]`` (find_constraints, or ``swept_lookups`` beyond a
    deforming mesh's reach).

    With ``in_reach``, reaching means phi < epsilon or phi + h u_n < epsilon (contacts at the
    start of a step); without, it means ending the step inside (phi + h u_n < 0). ``epsilon``:
    the terrains' contact bands. Inlined, handed two arrays, with nothing inlined in it: Numba
    counts a reference to each array an inline kernel is handed, and LLVM takes the counts out
    again only where nothing between lets a reference go (a kernel inlined within, handed
    arrays of its own, does). Handed the terrains' view and the positions for the swept
    lookups, it counted nine references up and down at every particle (CHANGELOG, issue 56).
    """
    best, best_phi, best_u_n, earliest = -1, 0.0, 0.0, np.inf
    nx = ny = nz = 0.0
    for t in range(epsilon.shape[0]):
        phi, mx, my, mz = (lookups[row, t, 0], lookups[row, t, 1], lookups[row, t, 2],
                           lookups[row, t, 3])
        u_n = u0 * mx + u1 * my + u2 * mz
        reached = phi + h * u_n   # distance at the end of the step
        if in_reach:
            touching = phi < epsilon[t] or reached < epsilon[t]
        else:
            touching = reached < 0.0
        if touching and reached < earliest:
            best, best_phi, best_u_n, earliest = t, phi, u_n, reached
            nx, ny, nz = mx, my, mz
    return best, best_phi, nx, ny, nz, best_u_n


@inline_kernel
def beyond_reach(lookups, i):
    """Whether a terrain's lookup at particle i answered infinity: a deforming mesh, beyond
    whose reach the step's path is asked instead (``swept_lookups``)."""
    for t in range(lookups.shape[1]):
        if lookups[i, t, 0] == math.inf:
            return True
    return False


@inline_kernel
def swept_lookups(terrains, epsilon, radius, lookups, x, i, u0, u1, u2, h, swept):
    """swept[0] = particle i's ``lookups``, each that answered infinity (beyond a deforming
    mesh's reach, with no normal to look ahead along) replaced by the lookup along the step's
    path (``swept_lookup``) of a particle moving at (u0, u1, u2); ``radius``: the particle's
    (model.terrain_offset[i])."""
    for t in range(epsilon.shape[0]):
        phi, mx, my, mz = lookups[i, t, 0], lookups[i, t, 1], lookups[i, t, 2], lookups[i, t, 3]
        if phi == math.inf:
            phi, mx, my, mz = swept_lookup(terrains, t, x, i, u0, u1, u2, h, radius,
                                           2.0 * epsilon[t])
        swept[0, t, 0], swept[0, t, 1], swept[0, t, 2], swept[0, t, 3] = phi, mx, my, mz


@inline_kernel
def swept_lookup(terrains, t, x, i, u0, u1, u2, h, radius, spacing):
    """(phi, normal) for particle i beyond a deforming mesh's reach: the first of the points
    x + s h u along the step (``spacing`` apart, s up to 1) that the lookup finds stands in, with
    the start's distance along its normal, phi_s - s h u . n; infinity if none. The reach is at
    least 4 contact bands, so points 2 bands apart cannot all miss a surface the path crosses,
    and a particle that moves less than that cannot reach the band: it is not asked. Without
    this a particle faster than reach / h would pass through unseen."""
    travel = h * math.sqrt(u0 * u0 + u1 * u1 + u2 * u2)
    if not travel >= spacing:
        return math.inf, 0.0, 1.0, 0.0
    count = min(int(math.ceil(travel / spacing)), MAX_SWEEP_POINTS)
    for k in range(1, count + 1):
        s = k / count
        phi, mx, my, mz = terrain_at(terrains, t, x[i, 0] + s * h * u0, x[i, 1] + s * h * u1,
                                     x[i, 2] + s * h * u2, radius)
        if phi != math.inf:
            return phi - s * h * (u0 * mx + u1 * my + u2 * mz), mx, my, mz
    return math.inf, 0.0, 1.0, 0.0
