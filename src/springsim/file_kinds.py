"""Which kind of file a command was given: a recording (an NPZ file) or a scene file, told
apart before either is read, so that each is refused by the reader that fits it."""
import os

NPZ_MAGIC = b"PK\x03\x04"   # an NPZ file is a ZIP archive


def is_recording_file(path) -> bool:
    """Whether ``path`` is a regular file that begins as an NPZ (ZIP) file does: a recording
    rather than a scene file, for the commands that take either."""
    text = os.fspath(path)
    if not os.path.isfile(text):
        return False
    try:
        with open(text, "rb") as file:
            return file.read(len(NPZ_MAGIC)) == NPZ_MAGIC
    except OSError:
        return False


def names_recording(path) -> bool:
    """Whether a command that takes a scene or a recording should read ``path`` as a recording:
    it ends in .npz, or it is a file that begins as an NPZ file does."""
    return os.fspath(path).lower().endswith(".npz") or is_recording_file(path)
