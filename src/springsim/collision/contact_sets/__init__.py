"""The contact sets: every touching stencil of a step gathered in one named value.

A stencil is four particles ``nodes`` with signed weights ``weights`` c that sum to zero, so
that d = sum_i c_i x_i runs from one side of the contact to the other, and a normal n.
``ImpulseContacts`` are the contacts at the end of a step (after_step.py), which the impulse
passes and the overlap correction answer (response/); ``SolveContacts`` the candidates of
backward Euler's solve (solve.py), which act as one-sided springs (response/penalty.py).
"""
from typing import NamedTuple

import numpy as np

# What a contact of the solve is (SolveContacts.shape), and a ball contact's passes: the narrow
# phase's, which builds the stencils (defined there so that it need not import this package)
from ..narrow_phase import (BALL_PASSES, BALL_POINT, BALL_SAMPLE, BALL_TRIANGLE,  # noqa: F401
                            EDGE_EDGE, POINT_TRIANGLE)

# The contacts after the step (after_step.py): their parameters
PASSES = 8          # Jacobi passes of the velocity impulses per step
CORRECTION = 0.5    # share of an overlap removed per step
PARAMS = 6          # numbers per contact: restitution, kinetic and static friction, share of
                    # the depth corrected, share of a stuck sliding taken back, passes


class ImpulseContacts(NamedTuple):
    """The touching stencils at the end of a step, which impulses and overlap corrections answer
    (contact_sets/after_step.py fills it, response/ reads it). K contacts."""

    nodes: np.ndarray     # (K, 4) int64: the stencil's particles (a ball's pads with its partner)
    weights: np.ndarray   # (K, 4): the signed weights c, summing to zero (0 for a pad)
    normal: np.ndarray    # (K, 3): unit normal, from the second side to the first
    depth: np.ndarray     # (K,) m: how far the pair is inside its rest distance
    params: np.ndarray    # (K, PARAMS): restitution, kinetic and static friction, share of the
                          # depth corrected a step, share of a stuck sliding taken back, passes


class SolveContacts(NamedTuple):
    """The candidate contacts of backward Euler's solve, penalty springs while active
    (contact_sets/solve.py fills it, response/penalty.py linearizes and solves with it)."""

    nodes: np.ndarray        # (K, 4) int64: the stencil's particles
    weights: np.ndarray      # (K, 4): the signed weights c at the linearization, summing to zero
    normal: np.ndarray       # (K, 3): unit normal at the linearization
    gap: np.ndarray          # (K,) m: g = n . sum_i c_i x_i - rest at the estimate (inf: never)
    coefficient: np.ndarray  # (K,) kg: h^2 k, the spring's stiffness times the step squared
    active: np.ndarray       # (K,) bool: in the active set (pushing)
    shape: np.ndarray        # (K,) int64: BALL_POINT, BALL_TRIANGLE, BALL_SAMPLE,
                             # POINT_TRIANGLE or EDGE_EDGE
    rest: np.ndarray         # (K,) m: the rest distance (radii, or the mean thickness)
