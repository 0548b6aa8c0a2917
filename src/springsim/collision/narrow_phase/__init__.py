"""Narrow phase: one stencil (nodes, weights, normal) per candidate pair that touches; after_step.py
at the end of a step, solve.py at the solve's Newton estimate.
"""
