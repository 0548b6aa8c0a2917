"""Wavefront OBJ: the take's first frame as one mesh (the rest pose of the point caches).

One object, a group (``g``) per body and per ball, vertices in the point caches' order (Blender's
importer keeps one object and that order unless told to split groups). Specified in the
"Object Files (.obj)" appendix of the Wavefront Advanced Visualizer manual: ``v x y z`` lines,
then ``f a b c`` with vertex numbers counted from 1.
"""
import io

import numpy as np

from .geometry import point_pieces, stacked_vertices, unique_names
from ..safe_files import staged_path

EXTENSIONS = (".obj",)
DESCRIPTION = "OBJ rest mesh: the first frame's body surfaces and balls"


def outputs(path) -> list:
    return [path]


def check_available() -> None:
    """No dependency."""


def write(take, path) -> list:
    pieces = point_pieces(take.layout, take.positions[0])
    with staged_path(path) as staged:
        write_obj(staged, pieces, stacked_vertices(pieces, take.positions[:1])[0], take.name)
    return [path]


def write_obj(path, pieces, vertices: np.ndarray, name: str, pose: str = "rest pose (frame 0)",
              faces: str | None = None) -> None:
    """``pieces`` (geometry.Piece) with their vertices stacked in ``vertices`` (N, 3), at
    ``pose`` (the header's words); ``faces``: their ``faces_text``, made once for a sequence."""
    text = io.StringIO()
    text.write(f"# springsim take {name}: {pose}, Y up, metres\no {_token(name)}\n")
    np.savetxt(text, vertices, fmt="v %.9g %.9g %.9g")
    text.write(faces_text(pieces) if faces is None else faces)
    with open(path, "x", encoding="utf-8") as file:
        file.write(text.getvalue())


def faces_text(pieces) -> str:
    """The ``g`` and ``f`` lines of ``pieces``: a group a piece, vertices counted from 1."""
    text, first = io.StringIO(), 1
    for piece, group in zip(pieces, unique_names(_token(p.name) for p in pieces)):
        text.write(f"g {group}\n")
        np.savetxt(text, piece.triangles + first, fmt="f %d %d %d")
        first += piece.vertex_count
    return text.getvalue()


def _token(name: str) -> str:
    return "_".join(str(name).split()) or "take"
