"""The position response after the impulses: each overlap reduced by a share of its depth, and a
surface contact that static friction held has its sliding during the step taken back, shared by
the stencil's particles with the impulses' mass splitting (impulses.py).
"""
import numpy as np

from ..._jit import kernel


@kernel
def correct_overlaps(inv_mass, x, start, contacts, stuck, mobility):
    """Move each touching stencil apart by its share of its depth (params[k, 3]), and take back
    params[k, 4] of the sliding of a stuck one during the step (all for surfaces, none for
    balls), shared like the impulses (module doc). All shifts are found from the same positions
    before any is made (Jacobi, as the impulses)."""
    nodes, weights, normal = contacts.nodes, contacts.weights, contacts.normal
    depth, params = contacts.depth, contacts.params
    shift = np.zeros((nodes.shape[0], 3))
    for k in range(nodes.shape[0]):
        if not mobility[k] > 0.0:
            continue
        push = params[k, 3] * max(depth[k], 0.0)   # the contact's share of its depth
        for c in range(3):
            shift[k, c] = push * normal[k, c]
        if stuck[k] and params[k, 4] > 0.0:
            slid0 = slid1 = slid2 = 0.0
            for i in range(4):
                n = nodes[k, i]
                slid0 += weights[k, i] * (x[n, 0] - start[n, 0])
                slid1 += weights[k, i] * (x[n, 1] - start[n, 1])
                slid2 += weights[k, i] * (x[n, 2] - start[n, 2])
            along = slid0 * normal[k, 0] + slid1 * normal[k, 1] + slid2 * normal[k, 2]
            back = params[k, 4]
            shift[k, 0] -= back * (slid0 - along * normal[k, 0])
            shift[k, 1] -= back * (slid1 - along * normal[k, 1])
            shift[k, 2] -= back * (slid2 - along * normal[k, 2])
        for c in range(3):
            shift[k, c] /= mobility[k]
    for k in range(nodes.shape[0]):
        for i in range(4):
            share = weights[k, i] * inv_mass[nodes[k, i]]
            for c in range(3):
                x[nodes[k, i], c] += share * shift[k, c]
