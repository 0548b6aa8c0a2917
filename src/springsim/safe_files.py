"""Files written whole or not at all, and output paths checked before the work that fills them.

Every writer (NPZ, CSV, JSON, plots, MP4, GIF, PNG folders) writes into a private staging folder
that ``tempfile.mkdtemp`` creates beside the target: an exclusive ``mkdir`` with a random name and
mode 0700, so no other user can plant a file or a symbolic link in it, and nothing in it follows
one. Only when the writer has finished without an error (and its data is on disk: fsync) is the
result renamed onto the target, which is atomic on one file system; a reader sees the old file or
the new one, never half. Any error, Ctrl-C or SIGTERM (``springsim.cli`` turns it into an
exception) removes the staging folder.

``check_output_path`` says up front, in one line, why a path cannot be written: a missing or
read-only folder (tried by making a staging folder there, since permission bits say nothing to
root), a name too long for the file system, a folder where a file is wanted.
"""
import contextlib
import os
import shutil
import tempfile
from pathlib import Path

from .errors import OutputFailed, require

STAGING_SUFFIX = ".part"


def check_output_path(key: str, path, *, folder: bool = False) -> Path:
    """Refuse (SceneError naming ``key``) a path that no writer here could create.

    ``folder``: the output is a folder (PNG frames), which must be new or empty.
    Returns the absolute path.
    """
    text = os.fspath(path)
    require(isinstance(text, str) and text.strip() != "" and "\0" not in text, key, path,
            "must be a file name")
    target = Path(os.path.abspath(text))
    parent = target.parent
    require(parent.is_dir(), key, text, f"the folder {parent} does not exist")
    require(os.access(parent, os.W_OK | os.X_OK), key, text,
            f"the folder {parent} is not writable")
    _probe(key, text, parent)
    longest = _limit(parent, "PC_NAME_MAX", 255)
    require(len(os.fsencode(target.name)) <= longest, key, text,
            f"the file name is {len(os.fsencode(target.name))} bytes long; this file system "
            f"allows at most {longest}")
    require(len(os.fsencode(str(target))) < _limit(parent, "PC_PATH_MAX", 4096), key, text,
            "the path is too long for this file system")
    if folder:
        require(not target.exists() or (target.is_dir() and not any(target.iterdir())), key,
                text, "must be a new or empty folder for PNG frames")
    else:
        require(not target.is_dir(), key, text, "is a folder; give a file name")
    return target


def check_output_folder(key: str, folder) -> Path:
    """Refuse a folder that files cannot be written into."""
    text = os.fspath(folder)
    path = Path(os.path.abspath(text))
    require(path.is_dir(), key, text, "must be an existing folder")
    require(os.access(path, os.W_OK | os.X_OK), key, text, "is not a writable folder")
    _probe(key, text, path)
    return path


def _probe(key: str, text: str, folder: Path) -> None:
    """Create and remove a staging folder in ``folder``, as the writers will: the permission
    bits say nothing to root, and some folders refuse new entries whatever they say (/proc,
    /sys, a read-only mount seen through a writable bind)."""
    try:
        os.rmdir(tempfile.mkdtemp(dir=folder, prefix=".springsim-probe.", suffix=STAGING_SUFFIX))
    except OSError as error:
        require(False, key, text, f"the folder {folder} is not writable ({error.strerror})")


class StagedOutput:
    """A path to write instead of ``target``: ``commit()`` renames it onto ``target``,
    ``discard()`` removes it (and is harmless after a commit).

    The staged path has the target's own name (writers that pick a format from the suffix still
    do) inside a private staging folder beside the target; with ``folder`` it is a new, empty
    folder. Failures become ``OutputFailed`` naming the target.
    """

    def __init__(self, target, *, folder: bool = False):
        self.target = Path(os.path.abspath(os.fspath(target)))
        try:
            self._staging = Path(tempfile.mkdtemp(dir=self.target.parent,
                                                  prefix=f".{self.target.name[:40]}.",
                                                  suffix=STAGING_SUFFIX))
            self.path = self._staging / self.target.name
            if folder:
                self.path.mkdir()
        except OSError as error:
            self.discard()
            raise OutputFailed(self.target, error) from None

    def commit(self) -> Path:
        try:
            _sync(self.path)
            _give_usual_mode(self.path)
            os.replace(self.path, self.target)
            _sync_folder(self.target.parent)
        except OSError as error:
            raise OutputFailed(self.target, error) from None
        finally:
            self.discard()
        return self.target

    def discard(self) -> None:
        staging = getattr(self, "_staging", None)
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)


@contextlib.contextmanager
def staged_path(path, *, folder: bool = False):
    """A path to write instead of ``path``; it becomes ``path`` if the block succeeds, and is
    removed otherwise (an error, Ctrl-C, SIGTERM). Write errors become ``OutputFailed``."""
    staged = StagedOutput(path, folder=folder)
    try:
        yield staged.path
    except OSError as error:
        if isinstance(error, OutputFailed):
            raise
        raise OutputFailed(staged.target, error) from None
    else:
        staged.commit()
    finally:
        staged.discard()


@contextlib.contextmanager
def staged_paths(paths):
    """``staged_path`` for several files that belong together (a point cache and its rest mesh):
    none is renamed onto its target unless every one of them was written."""
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(staged_path(path)) for path in paths]


@contextlib.contextmanager
def staged_files(paths):
    """Paths to write instead of ``paths``, all in one folder (a numbered sequence: hundreds of
    files, each too small for a staging folder of its own): once every one is written, all
    are put on disk, then renamed onto their targets; if any is not written, none is."""
    targets = [Path(os.path.abspath(os.fspath(path))) for path in paths]
    staged = StagedOutput(targets[0], folder=True)
    try:
        yield [staged.path / target.name for target in targets]
        for target in targets:
            _fsync(staged.path / target.name, os.O_RDONLY | os.O_NOFOLLOW)
        for target in targets:
            _give_usual_mode(staged.path / target.name)
            os.replace(staged.path / target.name, target)
        _sync_folder(targets[0].parent)
    except OSError as error:
        if isinstance(error, OutputFailed):
            raise
        raise OutputFailed(targets[0], error) from None
    finally:
        staged.discard()


@contextlib.contextmanager
def atomic_output(path):
    """A binary file object that becomes ``path`` only if the block finishes without an error."""
    with staged_path(path) as staged:
        with open(staged, "xb") as file:
            yield file


def _sync(path: Path) -> None:
    """Put a written file, or every file of a written folder, on disk before the rename."""
    for file in sorted(path.iterdir()) if path.is_dir() else [path]:
        _fsync(file, os.O_RDONLY | os.O_NOFOLLOW)


def _sync_folder(folder: Path) -> None:
    """Make a rename in ``folder`` durable (not every file system can sync a folder)."""
    with contextlib.suppress(OSError):
        _fsync(folder, os.O_RDONLY | os.O_DIRECTORY)


def _fsync(path: Path, flags: int) -> None:
    descriptor = os.open(path, flags)
    try:
        os.fsync(descriptor)
    finally:
        os.close(descriptor)


def _give_usual_mode(path: Path) -> None:
    """Files and folders as ``open``/``mkdir`` would make them (the staging folder is private,
    and mkstemp-style creation is 0600)."""
    mask = os.umask(0)
    os.umask(mask)
    os.chmod(path, (0o777 if path.is_dir() else 0o666) & ~mask)


def _limit(folder: Path, name: str, fallback: int) -> int:
    try:
        return os.pathconf(folder, name)
    except (OSError, ValueError):
        return fallback
