"""Continuous collision check: whether a step carried a point through a triangle or an edge past
an edge (crossing_check.py), which backward Euler answers by taking the step again in halves.
"""
