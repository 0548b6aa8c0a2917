"""The interactive viewer: a polyscope window with the course framework's control panel.

``controls.Controls`` holds what the panel changes and needs no window (tests drive it);
``window.Viewer`` (which imports polyscope) shows it.
"""
