"""Numbered OBJ files, one a frame: ``take_####.obj`` becomes take_0001.obj, take_0002.obj, ...

For a tool that reads no point cache, or an artist who wants each frame as a mesh (Houdini's
File SOP with ``$F4``, Blender's mesh-sequence add-ons). Each file is the rest mesh's OBJ
(obj.py) at its frame: the same vertices in the same order (every body surface, a mesh body's or
mesh cloth's own file vertices with their seam copies, then a sphere per ball) and the same
faces. The run of ``#`` before ``.obj`` is replaced by the frame's number, zero-padded to the
run's width, counting from the take's start frame (``export --start-frame``), as Blender fills an
output path's ``#``. Files of an earlier, longer sequence of the same name past the last frame
are left as they are: export into an empty folder to keep a sequence on its own.
"""
import re
from pathlib import Path

from ..errors import require
from ..safe_files import check_output_path, staged_files
from .geometry import point_pieces, stacked_vertices
from .obj import faces_text, write_obj
from .take import START_FRAME

EXTENSIONS = ("#.obj",)   # the path's ending that picks this format (export/__init__.py)
DESCRIPTION = "OBJ sequence (NAME_####.obj): one OBJ a frame, vertices in the point caches' order"
FRAME_NUMBER = re.compile(r"#+(?=\.obj$)", re.IGNORECASE)


def outputs(path) -> list:
    """The first file at the usual start frame stands for the sequence (its folder and name);
    ``write`` checks every frame's once it knows how many there are."""
    return [frame_path(path, START_FRAME)]


def check_available() -> None:
    """No dependency."""


def check_start_frame(path, start_frame: int, key: str) -> None:
    """Files are numbered from the start frame: it cannot be negative."""
    require(start_frame >= 0, key, str(path),
            f"an OBJ sequence numbers its files from the start frame, which is {start_frame}; "
            "give --start-frame 0 or more")


def frame_path(path, frame: int) -> Path:
    """``path`` with its run of ``#`` replaced by ``frame``, zero-padded to the run's width."""
    text = str(path)
    hashes = FRAME_NUMBER.search(text)
    width = hashes.end() - hashes.start()
    return Path(text[:hashes.start()] + f"{frame:0{width}d}" + text[hashes.end():])


def write(take, path) -> list:
    """Every frame's OBJ, all written or none."""
    first = take.start_frame
    check_start_frame(path, first, "export")
    paths = [frame_path(path, first + k) for k in range(take.frame_count)]
    check_output_path("export", paths[-1])   # the longest name; the folder was checked
    for target in paths:
        require(not target.is_dir(), "export", str(target), "is a folder; give a file name")
    pieces = point_pieces(take.layout, take.positions[0])
    points, faces = stacked_vertices(pieces, take.positions), faces_text(pieces)
    with staged_files(paths) as staged:
        for k, target in enumerate(staged):
            write_obj(target, pieces, points[k], take.name, f"frame {first + k}", faces)
    return paths
