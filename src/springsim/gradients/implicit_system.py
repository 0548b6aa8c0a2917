"""The filtered linear system of backward Euler's step with terrain contact, as the replay
(implicit_replay.py) solves it and the adjoint (implicit_contact.py) solves its transpose: the
springs' and terms' diagonal blocks, the friction dampers' blocks and share of the right-hand
side, the held components of a contact, and the reduced solve on the unconstrained ones."""
import numpy as np
from scipy import sparse

from ..implicit.constraints import CONTACT, FREE
from .solve import solve_reduced, spring_blocks
from . import terms


def tangential(u, n):
    """(I - n n^T) u per particle."""
    return u - np.einsum("ij,ij->i", u, n)[:, None] * n


def rowdot(u, w):
    return np.einsum("ij,ij->i", u, w)


def diagonal_blocks(physical, x_k, v_k, h):
    """Each particle's diagonal block of the springs' matrix A (P, 3, 3): the masses and drag,
    the terms' diagonal blocks and every spring's C = p l l^T + q I
    (physics.system_product)."""
    blocks = spring_blocks(physical, x_k, h)
    out = np.zeros((x_k.shape[0], 3, 3))
    np.add.at(out, physical.a, blocks)
    np.add.at(out, physical.b, blocks)
    out += (physical.solve_mass + h * physical.drag)[:, None, None] * np.eye(3)
    return out + terms.diagonal_blocks(physical, x_k, v_k, h)


def held(constraints, kind, u0):
    """z: the constrained components of ddv (hold_constrained): (floor - n . u0) n on contacts."""
    z = np.zeros_like(u0)
    contact = kind == CONTACT
    gap = constraints.floor[contact] - rowdot(u0[contact], constraints.normal[contact])
    z[contact] = gap[:, None] * constraints.normal[contact]
    return z


def friction_terms(kind, normal, c, u0):
    """(the dampers' blocks as a sparse matrix, their share of b: -c (I - n n^T) u0, u0 the
    velocity relative to the terrain's surface)."""
    on = (kind == CONTACT) & (c != 0.0)
    blocks = np.zeros((len(c), 3, 3))
    n = normal[on]
    blocks[on] = c[on, None, None] * (np.eye(3) - n[:, :, None] * n[:, None, :])
    count = len(c)
    matrix = sparse.bsr_matrix((blocks, np.arange(count), np.arange(count + 1)),
                               shape=(3 * count, 3 * count)).tocsr()
    share = np.zeros_like(u0)
    share[on] = -c[on, None] * tangential(u0[on], n)
    return matrix, share


def pushes(kind, normal, reaction):
    """n . R of each contact after a solve (0 elsewhere), R = A_sp ddv - b_sp: the friction's
    share of A ddv - b has no part along n."""
    return np.where(kind == CONTACT, rowdot(reaction, normal), 0.0)


def solve_step(physical, constraints, kind, matrix, b_sp, u0, c):
    """(ddv with S (A ddv - b) = 0 and its constrained components held (z), the reaction
    R = A_sp ddv - b_sp without the dampers, which the push and the update read)."""
    friction, share = friction_terms(kind, constraints.normal, c, u0 - constraints.surface)
    z = held(constraints, kind, u0)
    a = matrix + friction
    ddv = solve_reduced(a, b_sp + share, z, basis(kind, constraints.normal))
    return ddv, (matrix @ ddv.ravel()).reshape(ddv.shape) - b_sp


def basis(kind, normal):
    """Q: orthonormal columns spanning the components no constraint fixes (3P, r): a free
    particle's three axes, a contact's two tangents, none of a pinned one's, in particle
    order."""
    free, contact = np.nonzero(kind == FREE)[0], np.nonzero(kind == CONTACT)[0]
    width = np.zeros(len(kind), np.int64)
    width[free], width[contact] = 3, 2
    first = np.cumsum(width) - width   # each particle's first column
    axes, shape = np.arange(3), (len(contact), 2, 3)   # a contact's tangent k, component c
    rows = [(3 * free[:, None] + axes).ravel(),
            np.broadcast_to(3 * contact[:, None, None] + axes, shape).ravel()]
    cols = [(first[free][:, None] + axes).ravel(),
            np.broadcast_to(first[contact][:, None, None] + np.arange(2)[:, None], shape).ravel()]
    values = [np.ones(3 * len(free)), np.stack(tangents(normal[contact]), axis=1).ravel()]
    return sparse.csr_matrix((np.concatenate(values), (np.concatenate(rows),
                                                       np.concatenate(cols))),
                             shape=(3 * len(kind), int(width.sum())))


def tangents(n):
    """Two unit tangents of each normal (K, 3): across the axis the normal leans on least."""
    e = np.zeros_like(n)
    e[np.arange(len(n)), np.argmin(np.abs(n), axis=1)] = 1.0
    t1 = np.cross(n, e)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    return t1, np.cross(n, t1)
