"""Numbered OBJ files, one a frame: ``take_####.obj`` becomes take_0001.obj, take_0002.obj, ...

For a tool that reads no point cache, or an artist who wants each frame as a mesh (Houdini's
File SOP with ``$F4``, Blender's mesh-sequence add-ons). Each file is the rest mesh's OBJ
(obj.py) at its frame: the same vertices in the same order (every body surface, a mesh body's or
mesh cloth's own file vertices with their seam copies, then a sphere per ball) and the same
faces. The run of ``#`` before ``.obj`` is replaced by the frame's number, zero-padded to the
run's width, counting from the take's start frame (``export --start-frame``), as Blender fills an
output path's ``#``.
"""
import re
from pathlib import Path

from ..errors import require
from ..safe_files import staged_paths
from .geometry import point_pieces, stacked_vertices
from .obj import write_obj

EXTENSIONS = ("#.obj",)
DESCRIPTION = "OBJ sequence (NAME_####.obj): one OBJ a frame, vertices in the point caches' order"
FRAME_NUMBER = re.compile(r"#+(?=\.obj$)", re.IGNORECASE)


def outputs(path) -> list:
    """The first frame's file stands for the sequence: the same folder and name length."""
    return [frame_path(path, 0)]


def check_available() -> None:
    """No dependency."""


def frame_path(path, frame: int) -> Path:
    """``path`` with its run of ``#`` replaced by ``frame``, zero-padded to the run's width."""
    text = str(path)
    hashes = FRAME_NUMBER.search(text)
    width = hashes.end() - hashes.start()
    return Path(text[:hashes.start()] + f"{frame:0{width}d}" + text[hashes.end():])


def write(take, path) -> list:
    """Every frame's OBJ, all written or none."""
    first, count = take.start_frame, take.frame_count
    require(first >= 0, "export", str(path),
            f"an OBJ sequence numbers its files from the start frame, which is {first}; "
            "give --start-frame 0 or more")
    paths = [frame_path(path, first + k) for k in range(count)]
    pieces = point_pieces(take.layout, take.positions[0])
    points = stacked_vertices(pieces, take.positions)
    with staged_paths(paths) as staged:
        for k, target in enumerate(staged):
            write_obj(target, pieces, points[k], take.name, f"frame {first + k}")
    return paths
