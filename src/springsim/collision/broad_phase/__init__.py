"""Broad phase: the pairs that may touch, found without testing every pair (grid.py, the uniform
grid both searches use; balls.py; surfaces.py).
"""
