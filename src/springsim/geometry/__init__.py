"""Closest points and distances between a point, a triangle and segments: what every stage of
the collision pipeline, the deforming terrains and the attachments measure with. Below all of
them, so that none imports another through it.
"""
