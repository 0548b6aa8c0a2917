"""How backward Euler's contact replay (implicit_replay.py) sees the terrains: once per step, at
the step's start positions, each terrain where the step's end has it (the forward's
terrain_lookups.closest_terrain), whichever solve asks.

A deforming mesh's grid sees a point only within its reach (terrains/deforming_mesh.py): beyond,
the forward's lookup answers infinity and asks points y = x + sigma u along the step's path
instead (terrain_lookups.swept_lookup, sigma = s h), so that a fast particle cannot pass through
unseen. The first point that sees the surface gives the contact phi = d(y) - sigma u . n(y),
n = n(y), and no surface velocity (the start is beyond reach). Its cotangents reach x through
y, and the velocity u it looked along as sigma y_bar - sigma phi_bar n (``swept_vjp``). At the
step's start u is v; in a solve's update it is that solve's end velocity, whose share the
replay does not carry, so a contact swept there onto an edge or a corner (where the normal
turns, and phi and n depend on u) is refused in one line; on a face they do not depend on u.
"""
from typing import NamedTuple

import numpy as np

from ..errors import SceneError
from ..implicit.terrain_lookups import MAX_SWEEP_POINTS
from .clock import STEP_START
from .contact import along, followed
from .terrain_shapes import STRAIGHT_UP, surface_velocity


class Lookup(NamedTuple):
    """A terrain as the step's start sees it, for each particle: where it looked (the start's
    position, or a point along a swept path) and how far ahead along that path."""

    terrain: int
    shape: object         # terrain_shapes' shape
    phi: np.ndarray       # (P,) m, infinite where the forward's lookup finds nothing
    normal: np.ndarray    # (P, 3)
    surface: object       # (P, 3) m/s, the surface's velocity there, or None: it stands still
    at: np.ndarray        # (P, 3) m, the point looked up: y = x + sigma u (x where not swept)
    ahead: np.ndarray     # (P,) s, sigma: 0 where not swept


def seen(shape, x) -> np.ndarray:
    """(K,) whether the forward's lookup finds the terrain from each point: everywhere, but for
    a deforming mesh beyond its reach."""
    return shape.seen(x) if hasattr(shape, "seen") else np.ones(len(x), bool)


def look_up(physical, x, v, h):
    """[Lookup] of every followed terrain at the positions x, where the force time has it (the
    step's end: a moving terrain's pose then, as the forward's step moves the world first),
    a free particle the lookup does not see asked along its path at v."""
    offset = physical.planes.offset
    lookups = []
    for t, shape in followed(physical.planes):
        phi, normal = shape.distance(x, offset), np.array(shape.normals(x), float)
        surface = surface_velocity(shape, x)
        lookup = Lookup(t, shape, phi, normal, surface, x.copy(), np.zeros(len(x)))
        hidden = ~seen(shape, x)
        if hidden.any():
            phi[hidden], normal[hidden], surface[hidden] = np.inf, STRAIGHT_UP, 0.0
            lookup = swept(physical, lookup, x, v, h, np.nonzero(hidden & physical.free)[0])
        lookups.append(lookup)
    return lookups


def swept(physical, lookup: Lookup, x, u, h, rows) -> Lookup:
    """The lookup with each of ``rows`` (particles it does not see) asked along its path at u,
    as terrain_lookups.swept_lookup asks: points ``spacing`` (2 bands) apart up to the step's end,
    the first that sees the surface giving phi, n and the point; infinity if none."""
    if not len(rows):   # asked at every solve's update, of every terrain
        return lookup
    spacing = 2.0 * float(physical.planes.epsilon[lookup.terrain])
    phi, normal, at, ahead = (lookup.phi.copy(), lookup.normal.copy(), lookup.at.copy(),
                              lookup.ahead.copy())
    phi[rows], normal[rows], at[rows], ahead[rows] = np.inf, STRAIGHT_UP, x[rows], 0.0
    travel = h * np.sqrt(np.einsum("ij,ij->i", u[rows], u[rows]))
    rows, travel = rows[travel >= spacing], travel[travel >= spacing]
    count = np.minimum(np.ceil(travel / spacing), MAX_SWEEP_POINTS).astype(np.int64)
    for k in range(1, int(count.max(initial=0)) + 1):
        asking = np.nonzero((k <= count) & np.isinf(phi[rows]))[0]
        if not len(asking):
            break
        sigma = k / count[asking] * h
        points = x[rows[asking]] + sigma[:, None] * u[rows[asking]]
        found = seen(lookup.shape, points)
        hit, sigma, points = rows[asking[found]], sigma[found], points[found]
        normal[hit] = lookup.shape.normals(points)
        phi[hit] = (lookup.shape.distance(points, physical.planes.offset[hit])
                    - sigma * along(u[hit], normal[hit]))
        at[hit], ahead[hit] = points, sigma
    return lookup._replace(phi=phi, normal=normal, at=at, ahead=ahead)


def unseen(lookup: Lookup) -> np.ndarray:
    """(P,) the particles whose start the lookup does not see (swept, or found nothing)."""
    return (lookup.ahead > 0.0) | np.isinf(lookup.phi)


def refuse_turning(physical, lookup: Lookup, i):
    """Refuse a contact that a solve's update sweeps particle i into where the terrain's normal
    turns (module doc)."""
    curvature = lookup.shape.curvature(lookup.at[i][None])
    if curvature is not None and np.any(curvature != 0.0):
        raise SceneError(f"terrains.{lookup.terrain}", "MeshTerrain",
                         f"takes particle {i} onto an edge or a corner within a solve of the "
                         f"step at {float(physical.clock[STEP_START]):.6g} s, from beyond its "
                         "reach, which gradients do not follow under implicit_euler: try a "
                         "smaller dt, or rk4")


def swept_vjp(shape, at, sigma, n, u, phi_bar, n_bar):
    """(x_bar, u_bar) of swept contacts (module doc) looked up at ``at`` = x + sigma u, from
    the cotangents of their phi and n."""
    turning = shape.curvature(at)   # (dn/dy)^T
    y_bar = phi_bar[:, None] * n + np.einsum("kij,kj->ki", turning,
                                             n_bar - (phi_bar * sigma)[:, None] * u)
    return y_bar, sigma[:, None] * (y_bar - phi_bar[:, None] * n)

