"""The velocity response after the step, in Jacobi passes (the post-step pass:
collision/pipeline.py).

Every contact's impulse is computed from the same velocities, then all are applied. With
W = sum_i c_i^2 n_i / m_i, a contact approaching at v_N = n . sum_i c_i v_i < 0 gets the normal
impulse that brings v_N to -e v_N (its first pass's), and a Coulomb friction impulse against the
tangential velocity that sticks (stops it) while the accumulated friction stays within the
static friction times the accumulated normal impulse, else slides with the kinetic friction
times it. Each contact's impulse is shared by its stencil, particle i getting c_i / m_i of it.
n_i is how many contacts particle i takes part in: each contact sees 1 / n_i of its mass (mass
splitting, Tonge, Benevolenski and Voroshilov 2012), so that contacts sharing particles do not
add up to several times the push, and the passes converge.

Why Jacobi and not one contact after another (Gauss-Seidel): the result would depend on the
contacts' order, so on the particle numbering, and a symmetric scene would not stay symmetric
(tests/test_ball_contact_order.py). Every impulse acts with weights summing to zero, so momentum
is conserved to rounding.

Under backward Euler the solve's penalty springs (penalty.py) take part of the approach speed
first, so restitution reflects only what is left.
"""
import math

import numpy as np

from ..._jit import inline_kernel, kernel


@kernel
def split_mobilities(inv_mass, nodes, weights):
    """(K,) W = sum_i c_i^2 n_i / m_i, each particle's mass split among the n_i contacts it
    takes part in (module doc)."""
    count = np.zeros(inv_mass.shape[0], np.int32)
    for k in range(nodes.shape[0]):
        for i in range(4):
            if weights[k, i] != 0.0:   # a ball's stencil pads its two nodes with zeros
                count[nodes[k, i]] += 1
    mobility = np.empty(nodes.shape[0])
    for k in range(nodes.shape[0]):
        total = 0.0
        for i in range(4):
            total += weights[k, i] ** 2 * inv_mass[nodes[k, i]] * count[nodes[k, i]]
        mobility[k] = total
    return mobility


@kernel
def apply_impulses(inv_mass, v, contacts, mobility):
    """The Jacobi passes of normal and friction impulses (module doc; each contact takes part in
    params[k, 5] of them; ``mobility``: split_mobilities); returns which contacts stuck (static
    friction held them) in their last pass."""
    return impulse_passes(inv_mass, v, contacts, mobility, np.zeros(contacts.nodes.shape[0]), True)


@kernel
def apply_friction(inv_mass, v, contacts, pushed):
    """The friction passes of ``apply_impulses`` alone, each contact's normal impulse given
    (``pushed``, N s: implicit_euler's penalty contacts push inside the solve,
    collision/response/solve_friction.py); returns which stuck."""
    mobility = split_mobilities(inv_mass, contacts.nodes, contacts.weights)
    return impulse_passes(inv_mass, v, contacts, mobility, pushed, False)   # never writes pushed


@kernel
def impulse_passes(inv_mass, v, contacts, mobility, pushed, push):
    """Jacobi passes, as many as the contact that takes most (params[:, 5]): friction against
    the accumulated normal impulse ``pushed``, plus, if ``push``, the normal impulses that stop
    each approach (adding to ``pushed``)."""
    nodes, weights = contacts.nodes, contacts.weights
    normal, params = contacts.normal, contacts.params
    count = nodes.shape[0]
    stuck = np.zeros(count, np.bool_)
    impulse = np.zeros((count, 3))      # this pass's, per contact
    rubbed = np.zeros((count, 3))       # friction impulse applied so far
    target = np.zeros(count)            # normal velocity wanted: -e (first approach), or 0
    relative = np.empty(3)
    passes = 0
    for k in range(count):
        passes = max(passes, int(params[k, 5]))
    for sweep in range(passes):
        for k in range(count):
            impulse[k, 0] = impulse[k, 1] = impulse[k, 2] = 0.0
            if not (mobility[k] > 0.0 and sweep < params[k, 5]):
                continue   # every particle of the stencil pinned, or its passes done
            for c in range(3):
                relative[c] = 0.0
                for i in range(4):
                    relative[c] += weights[k, i] * v[nodes[k, i], c]
            approach = relative[0] * normal[k, 0] + relative[1] * normal[k, 1] \
                + relative[2] * normal[k, 2]
            j = 0.0
            if push:
                if sweep == 0:
                    target[k] = -params[k, 0] * min(approach, 0.0)   # restitution
                j = max(target[k] - approach, 0.0) / mobility[k]
                pushed[k] += j
            stuck[k] = friction_impulse(k, params, relative, approach, normal, mobility[k],
                                        pushed[k], rubbed, impulse)
            for c in range(3):
                impulse[k, c] += j * normal[k, c]
        for k in range(count):
            for i in range(4):
                share = weights[k, i] * inv_mass[nodes[k, i]]
                for c in range(3):
                    v[nodes[k, i], c] += share * impulse[k, c]
    return stuck


@inline_kernel
def friction_impulse(k, params, relative, approach, normal, mobility, pushed, rubbed, impulse):
    """Set impulse[k] to this pass's friction: the change of the accumulated friction ``rubbed``
    that stops the sliding, kept within the static friction (params[k, 2]) x ``pushed`` or else
    cut to the kinetic (params[k, 1]) x ``pushed`` (Coulomb; ``mobility`` is the split W).
    Returns whether it sticks (never without friction)."""
    kinetic, static = params[k, 1], params[k, 2]
    w0 = rubbed[k, 0] - (relative[0] - approach * normal[k, 0]) / mobility
    w1 = rubbed[k, 1] - (relative[1] - approach * normal[k, 1]) / mobility
    w2 = rubbed[k, 2] - (relative[2] - approach * normal[k, 2]) / mobility
    size = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    sticks = size <= static * pushed
    if not sticks:
        cut = kinetic * pushed / size
        w0, w1, w2 = w0 * cut, w1 * cut, w2 * cut
    impulse[k, 0], impulse[k, 1], impulse[k, 2] = (w0 - rubbed[k, 0], w1 - rubbed[k, 1],
                                                   w2 - rubbed[k, 2])
    rubbed[k, 0], rubbed[k, 1], rubbed[k, 2] = w0, w1, w2
    return sticks and static > 0.0   # a frictionless contact has no sliding to take back
