"""Closest points and distances between a point, a triangle and segments: what every stage of
the pipeline measures with.
"""
