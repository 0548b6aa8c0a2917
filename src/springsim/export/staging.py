"""Files written whole or not at all, and output paths checked before any work.

A stand-in with the same names and signatures as rel-cli's ``springsim.safe_files`` (being
written in parallel), so that the exporters switch to it by changing one import.

``staged_path`` gives a path with the target's own name (writers that pick a format from the
suffix, such as USD, still do) inside a private staging folder that ``tempfile.mkdtemp`` creates
beside the target (an exclusive mkdir, mode 0700: nobody can plant a file or link in it). When the
block finishes, the file is synced and renamed onto the target, which is atomic on one file
system; on any error the staging folder is removed and the old target is left as it was.
"""
import contextlib
import os
import shutil
import tempfile
from pathlib import Path

from ..errors import require


def check_output_path(key: str, path) -> Path:
    """Refuse (SceneError naming ``key``) a file path that cannot be written; the absolute path."""
    text = os.fspath(path)
    require(text.strip() != "" and "\0" not in text, key, path, "must be a file name")
    target = Path(os.path.abspath(text))
    require(target.parent.is_dir(), key, text, f"the folder {target.parent} does not exist")
    require(os.access(target.parent, os.W_OK | os.X_OK), key, text,
            f"the folder {target.parent} is not writable")
    require(not target.is_dir(), key, text, "is a folder; give a file name")
    return target


@contextlib.contextmanager
def staged_path(path):
    """A path to write instead of ``path``; it becomes ``path`` if the block succeeds."""
    target = Path(os.path.abspath(os.fspath(path)))
    staging = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name[:40]}.",
                                    suffix=".part"))
    try:
        staged = staging / target.name
        yield staged
        descriptor = os.open(staged, os.O_RDONLY | os.O_NOFOLLOW)
        try:
            os.fsync(descriptor)
        finally:
            os.close(descriptor)
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(staged, 0o666 & ~mask)    # as open() would have made it
        os.replace(staged, target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)


@contextlib.contextmanager
def staged_paths(paths):
    """``staged_path`` for several files that belong together (a point cache and its rest mesh):
    they are renamed onto their targets only when all of them have been written."""
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(staged_path(path)) for path in paths]
