"""springsim inside Blender: a Blender 4.2+ extension that simulates the objects given a
springsim role (cloth, jelly body, collider) in springsim's own process and plays the take back
through a Mesh Cache modifier per object.

springsim and Numba are never imported here: the scene goes to springsim as a folder
(scene_export.py), the run is a subprocess (runner.py, worker.py) and the take comes back as PC2
point caches (point_cache.py). ``import springsim_blender; springsim_blender.register()`` loads it
into a running Blender (or bpy as a module) without installing it.
"""
import bpy

from . import operators, panels, properties

CLASSES = (*operators.CLASSES, *panels.CLASSES)


def register():
    properties.register()
    for cls in CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
    properties.unregister()
