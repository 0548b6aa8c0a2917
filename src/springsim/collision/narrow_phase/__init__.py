"""Narrow phase: one stencil (nodes, weights, normal) per candidate pair that touches; after_step.py
at the end of a step, solve.py at the solve's Newton estimate.

The kinds of stencil and the ball contacts' passes are defined here, below the contact sets
that gather the stencils (contact_sets/ reads them from here and passes them on), so that the
stages import one way: contact_sets/ imports narrow_phase/, never the other way round.
"""

# What a contact of the solve is (its ``shape``): how its weights and normal are found (solve.py)
BALL_POINT = 0       # a ball (node 0) and a point (node 1): c = (1, -1, 0, 0)
BALL_TRIANGLE = 1    # a ball and a sheet triangle: c = (1, -w_0, -w_1, -w_2)
POINT_TRIANGLE = 2   # a surface point and a surface triangle: c = (1, -w_0, -w_1, -w_2)
EDGE_EDGE = 3        # two surface edges: c = (1 - s, s, -(1 - t), -t)
BALL_SAMPLE = 4      # a ball and a sheet triangle's centre: c = (1, -1/3, -1/3, -1/3)

BALL_PASSES = 1     # Jacobi passes of a ball's contacts after the step (after_step.py says why)
