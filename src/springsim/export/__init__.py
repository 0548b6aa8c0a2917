"""Exporters: a recording (a Take) to files that Blender, Houdini and Omniverse open.

An open set: each format is one module here with ``EXTENSIONS``, ``DESCRIPTION``,
``check_available()`` (a SceneError when a dependency is missing), ``outputs(path)`` (the files
a write makes) and ``write(take, path)`` (returns the paths written, each whole or not at all);
the path's ending chooses the module, the longest that matches (``take_####.obj`` is an OBJ
sequence, ``take.obj`` one OBJ).
A new format is a new module and its name in ``FORMAT_MODULES``.
"""
import importlib
import itertools
import os
import re

from ..errors import require
from .geometry import point_pieces
from ..safe_files import check_output_path
from .take import Take, is_recording_file, load_take, names_recording, resampled, take_from_arrays

FORMAT_MODULES = ("usd", "mdd", "pc2", "obj", "obj_sequence")

__all__ = ["Take", "check_exports", "check_target", "export", "export_recording", "exporter_for",
           "extensions", "is_recording_file", "listed", "load_take", "names_recording",
           "resampled", "take_from_arrays"]


def _modules():
    return [importlib.import_module(f"{__name__}.{name}") for name in FORMAT_MODULES]


def extensions() -> dict:
    """{".usd": module, ...} for every format."""
    return {extension: module for module in _modules() for extension in module.EXTENSIONS}


def exporter_for(path, key: str = "export"):
    """The format module that writes ``path`` (by its longest matching ending); a SceneError if
    none does."""
    name = os.fspath(path).lower()
    known = extensions()
    endings = [ending for ending in known if name.endswith(ending)]
    require(len(endings) > 0, key, os.fspath(path),
            "must end in one of " + ", ".join(known) + " (the ending picks the format)")
    return known[max(endings, key=len)]


def check_target(path, key: str = "export"):
    """Everything about an export target that can be checked before any work: the format is
    known and its dependency installed, and the file (and a cache's rest mesh) can be written."""
    module = exporter_for(path, key)
    module.check_available()
    for output in module.outputs(path):
        check_output_path(key, output)
    return module


def listed(paths) -> str:
    """The paths written, for a summary line, each once (an .mdd and a .pc2 of one take share
    their rest-pose .obj): a numbered sequence (obj_sequence.py) as its first and last file and
    its count, not a name a frame."""
    def sequence(path) -> str:
        return re.sub(r"\d+(?=\.obj$)", "#", os.fspath(path), flags=re.IGNORECASE)

    parts = []
    for _, group in itertools.groupby(dict.fromkeys(map(os.fspath, paths)), key=sequence):
        group = list(group)
        parts.append(f"{group[0]} to {group[-1]} ({len(group)} files)" if len(group) > 2
                     else ", ".join(group))
    return ", ".join(parts)


def check_exports(paths, key: str = "export") -> None:
    for path in paths:
        check_target(path, key)


def export_recording(recording, paths, key: str = "export") -> list[str]:
    """Export a ``recording.Recording`` to each of ``paths``; the paths written."""
    if not paths:
        return []
    take = take_from_arrays(recording.arrays(), recording.scene)
    return [str(written) for path in paths for written in export(take, path, key)]


def export(take: Take, path, key: str = "export") -> list:
    """Write ``take`` to ``path`` in the format its ending names; the paths written."""
    module = check_target(path, key)
    check_memory(take, key, path)
    return module.write(take, path)


def check_memory(take: Take, key: str, path) -> None:
    """Refuse up front an export whose vertices at every frame (float64 and a float32 copy)
    would not fit in half the machine's memory."""
    vertices = sum(piece.vertex_count for piece in point_pieces(take.layout, take.positions[0]))
    needed = take.frame_count * vertices * 3 * (8 + 4)
    try:
        available = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return   # no way to tell on this system
    require(needed <= available / 2, key, os.fspath(path),
            f"exporting {take.frame_count} frames of {vertices} vertices needs "
            f"{needed / 1e9:.1f} GB of the machine's {available / 1e9:.1f} GB; record fewer "
            "frames (--fps, --duration)")
