"""Scene files: built-in names, TOML files and ``--set key=value`` overrides, all checked up front.

A scene file says what a preset says (see docs/scene-files.md)::

    name = "my-drop"
    integrator = "rk4"
    dt = 0.001

    [[bodies]]
    type = "cube"
    particles_per_edge = 8
    [bodies.structural]
    ks = 3000.0

    [[terrains]]
    type = "plane"

The mapping is generic over the dataclasses (scene_values.py), so that a new body kind needs only
its line in ``scene_values.BODY_TYPES`` (terrain kinds come from ``terrains.TERRAIN_TYPES``):

- a table's keys are its dataclass's fields; a key it does not give keeps its default;
- a field holding a dataclass is a sub-table (``[bodies.structural]``), and the keys it gives
  replace those of the default; a list of dataclasses is an array of tables (``[[bodies.balls]]``);
- the type of a value is the field's annotation (``int``, ``float``, ``bool``, ``str``,
  ``tuple[float, ...]``, ``str | list``, a dataclass). Where the annotation is a bare ``tuple`` or
  ``list``, its default says what it holds: floats make a vector of that length (``gravity``),
  tuples a list of such vectors, dataclasses a list of tables, ints or nothing a list of whole
  numbers of any length (``pinned``).

Overrides address list items by index: ``bodies.0.particles_per_edge=7``,
``terrains.0.friction=0.5``, ``bodies.0.structural.ks=3000``, ``gravity.1=-1.62``. Values are TOML
values (``1e-3``, ``true``, ``[0, -1.62, 0]``, ``{ks = 10, kd = 1}``); a bare word is a string.

This module reads; the overrides (scene_overrides.py), the writer back to TOML (scene_toml.py)
and the list of every key for the documentation (scene_schema.py) have modules of their own,
whose public names it gives too.
"""
import dataclasses
import os
import stat
import tomllib
import typing
from pathlib import Path

from .errors import SceneError, require
from .file_kinds import is_recording_file
from .presets import MESHES, PRESETS, preset
from .scene import Scene
# the parts of a scene file's life that have modules of their own, named here too: the
# overrides, the writer and the list of keys
from .scene_overrides import apply_override, parse_value, set_path  # noqa: F401
from .scene_schema import SceneKey, scene_keys  # noqa: F401
from .scene_toml import scene_to_toml, toml_value, type_name  # noqa: F401
from .scene_values import BODY_TYPES, TYPED_LISTS, merge_table  # noqa: F401
from .terrains import TERRAIN_TYPES  # noqa: F401  (the registries, as the readers name them)


MAX_SCENE_BYTES = 16 * 2 ** 20   # a scene file is a few kB; 16 MB leaves room for mesh tables
# ``file = "builtin:torus.obj"``: a mesh installed with springsim (presets.MESHES), found
# wherever springsim is installed, so a printed built-in scene runs from any folder
BUILTIN_MESH = "builtin:"


def load_scene(name_or_path, overrides=()) -> Scene:
    """A built-in scene or a TOML scene file, with ``"dotted.key=value"`` overrides, validated."""
    text = str(name_or_path)
    names_step = True
    if text in PRESETS:
        scene = preset(text)
    elif text.endswith(".toml") or Path(text).is_file():
        scene, names_step = read_scene_file(Path(text)), _names_step(Path(text))
    else:
        raise SceneError("scene", text, "must be a .toml scene file or one of "
                         + ", ".join(PRESETS))
    for override in overrides:
        scene = apply_override(scene, override)
        names_step |= str(override).partition("=")[0].strip() == "dt"
    scene = builtin_meshes_found(scene)   # an override may name one too
    scene.validate()
    if not names_step:
        scene = with_automatic_step(scene)
    return scene


def _names_step(path: Path) -> bool:
    """Whether the scene file gives its own ``dt``."""
    return "dt" in tomllib.loads(read_text_safely(path))


def with_automatic_step(scene: Scene) -> Scene:
    """``scene`` with the step step_size.py chooses, said in one line (a warning, which the
    command line prints as one line)."""
    import warnings

    from .step_size import automatic_step

    estimate = automatic_step(scene)
    warnings.warn(f"the scene gives no dt: dt = {estimate.dt:.3g} s, from {estimate.basis}",
                  AutomaticStep, stacklevel=user_stacklevel())
    return dataclasses.replace(scene, dt=estimate.dt)


def user_stacklevel() -> int:
    """The ``stacklevel`` that makes a warning from the function calling this one name the
    first caller outside springsim (the user's line, however deep in springsim the warning
    starts): Python 3.12's ``skip_file_prefixes``, which 3.11 lacks."""
    import sys

    package = str(Path(__file__).resolve().parent) + os.sep
    frame, level = sys._getframe(2), 2   # level 1 is the function that warns
    while frame is not None and str(Path(frame.f_code.co_filename).resolve()).startswith(
            package):
        frame, level = frame.f_back, level + 1
    return level


class AutomaticStep(UserWarning):
    """A scene file named no dt, and one was chosen (step_size.py)."""


def read_scene_file(path: Path) -> Scene:
    require(not is_recording_file(path), "scene", str(path),
            "is a recording (an NPZ file), not a scene file; `springsim render`, `export` and "
            "`play` read recordings")
    try:
        table = tomllib.loads(read_text_safely(path))
    except FileNotFoundError:
        raise SceneError("scene", str(path), "no such file; give a .toml scene file or one of "
                         + ", ".join(PRESETS)) from None
    except UnicodeDecodeError:
        raise SceneError("scene", str(path), "is neither a scene file (it is not UTF-8 text) nor "
                         "a recording (it is not an NPZ file)") from None
    except OSError as error:
        raise SceneError("scene", str(path), f"cannot be read ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise SceneError("scene", str(path), f"is not valid TOML: {error}") from None
    # A file that does not name its scene is named after itself (and so is its output).
    return files_relative_to(scene_from_table({"name": path.stem, **table}), path.parent)


def files_relative_to(scene: Scene, folder: Path) -> Scene:
    """The scene with every body's and terrain's relative ``file`` (a mesh), and every relative
    point cache of theirs or their pins' (``animation.file``), made relative to ``folder``, the
    scene file's: a scene file and its meshes move together."""
    items = [*scene.bodies, *scene.terrains]
    items += [item.animation for item in items if getattr(item, "animation", None)]
    items += [pin.animation for body in scene.bodies for pin in getattr(body, "pins", [])
              if getattr(pin, "animation", None)]
    for item in items:
        file = getattr(item, "file", None)
        if isinstance(file, str) and file and not Path(file).expanduser().is_absolute():
            item.file = str(folder / file)
    return scene


def read_text_safely(path: Path) -> str:
    """The text of a regular file of at most MAX_SCENE_BYTES, checked before it is read.

    Opened without blocking (a FIFO would wait for a writer) and checked on the open file (not on
    the name, which could change in between): a FIFO, a device (a link to /dev/zero), a folder or
    a file over the limit is refused with one line.
    """
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        status = os.fstat(descriptor)
        require(stat.S_ISREG(status.st_mode), "scene", str(path),
                f"is {_file_kind(status.st_mode)}, not a regular file; give a .toml scene file")
        require(status.st_size <= MAX_SCENE_BYTES, "scene", str(path),
                f"is {status.st_size:,} bytes; a scene file may have at most "
                f"{MAX_SCENE_BYTES:,} ({MAX_SCENE_BYTES // 2**20} MB)")
        data = b""
        while len(data) <= MAX_SCENE_BYTES and (chunk := os.read(descriptor, 2 ** 20)):
            data += chunk
    finally:
        os.close(descriptor)
    require(len(data) <= MAX_SCENE_BYTES, "scene", str(path),
            f"grew beyond {MAX_SCENE_BYTES:,} bytes while being read")
    return data.decode("utf-8")


def _file_kind(mode: int) -> str:
    kinds = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
             (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
             (stat.S_ISSOCK, "a socket"))
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def scene_from_table(table: dict) -> Scene:
    """A Scene from a parsed TOML document; every key and value is checked."""
    return builtin_meshes_found(merge_table(Scene(), table, ""))


def _mesh_files(scene: Scene):
    """(key, item) for every body and terrain that has a ``file``, and every point cache of
    theirs or their pins' (an ``animation`` with a ``file``)."""
    for list_name in ("bodies", "terrains"):
        for index, item in enumerate(getattr(scene, list_name)):
            key = f"{list_name}.{index}"
            if isinstance(getattr(item, "file", None), str):
                yield f"{key}.file", item
            owners = [(key, item)] + [(f"{key}.pins.{n}", pin)
                                      for n, pin in enumerate(getattr(item, "pins", None) or [])]
            for owner_key, owner in owners:
                animation = getattr(owner, "animation", None)
                if isinstance(getattr(animation, "file", None), str):
                    yield f"{owner_key}.animation.file", animation


class MadeFile(typing.NamedTuple):
    path: Path                      # where it is made, made or not
    make: typing.Callable[[], Path]  # make it if it is not there yet; its path


def _made_files() -> dict:
    """{name: MadeFile} for the files springsim makes on first use rather than installs: the
    walking figure of the cape scene (walking_figure.py), made in the user's cache."""
    from .walking_figure import figure_files, figure_paths

    paths = figure_paths()
    return {"walking-figure.obj": MadeFile(paths.mesh, lambda: figure_files().mesh),
            "walking-figure.pc2": MadeFile(paths.cache, lambda: figure_files().cache)}


def builtin_meshes_found(scene: Scene) -> Scene:
    """The scene with each ``builtin:NAME`` file replaced by that installed (or made) file's
    path."""
    for key, item in _mesh_files(scene):
        if item.file.startswith(BUILTIN_MESH):
            name = item.file[len(BUILTIN_MESH):]
            made = _made_files()
            installed = sorted(path.name for path in MESHES.iterdir() if path.is_file())
            require(name in installed or name in made, key, item.file,
                    "is not a file installed with springsim; those are "
                    + ", ".join(BUILTIN_MESH + each for each in [*installed, *made]))
            item.file = str(made[name].make() if name in made else MESHES / name)
    return scene


def with_builtin_mesh_names(scene: Scene) -> Scene:
    """A copy of the scene whose files that are meshes installed with springsim (or the files it
    makes: the walking figure) are written ``builtin:NAME`` (which the reader finds wherever
    springsim is installed), not by this installation's path: what `springsim scenes` prints
    runs from any folder."""
    import copy

    scene = copy.deepcopy(scene)
    made = {str(each.path.expanduser().resolve()): name for name, each in _made_files().items()}
    for _, item in _mesh_files(scene):
        if item.file and not item.file.startswith(BUILTIN_MESH):
            path = Path(item.file).expanduser().resolve()
            if path.parent == MESHES and path.is_file():
                item.file = BUILTIN_MESH + path.name
            elif str(path) in made:
                item.file = BUILTIN_MESH + made[str(path)]
    return scene
