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
"""
import dataclasses
import json
import numbers
import os
import stat
import tomllib
import types
import typing
from pathlib import Path

import numpy as np

from .errors import SceneError, require
from .file_kinds import is_recording_file
from .presets import MESHES, PRESETS, preset
from .scene import Scene
from .scene_values import (BODY_TYPES, TYPED_LISTS, convert_field, convert_like,  # noqa: F401
                           describe, init_fields, merge_table, typed_item, is_integer,
                           is_table_list, join_key, strip_optional)
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


def apply_override(scene: Scene, override: str) -> Scene:
    """A copy of ``scene`` with the ``"dotted.key=value"`` override applied."""
    key, separator, raw = str(override).partition("=")
    key = key.strip()
    require(separator == "=" and key != "", "--set", override,
            "must be KEY=VALUE, for example bodies.0.particles_per_edge=7")
    return set_path(scene, key.split("."), parse_value(raw.strip()), "", key)


def parse_value(text: str):
    """A TOML value (number, boolean, string, array, inline table), else a number as Python
    writes it (``.5``, which TOML refuses), else the bare text as a string."""
    try:
        return tomllib.loads(f"value = {text}")["value"]
    except tomllib.TOMLDecodeError:
        pass
    for number in (int, float):
        try:
            return number(text)
        except ValueError:
            pass
    return text


# --- overrides: one value deep inside the scene ---------------------------------------------------

def set_path(node, parts: list[str], value, prefix: str, full_key: str):
    """A copy of ``node`` (a dataclass, list or tuple) with the value at ``parts`` replaced.

    ``prefix`` is the key of ``node``; errors about the path name the whole ``full_key``.
    """
    head, rest = parts[0], parts[1:]
    key = join_key(prefix, head)
    if isinstance(node, (list, tuple)):
        index = _list_index(node, head, prefix, full_key, value)
        items = list(node)
        if rest:
            items[index] = _descend(items[index], rest, value, key, full_key)
        elif prefix in TYPED_LISTS:
            items[index] = typed_item(value, prefix, items[index], key)
        else:
            items[index] = convert_like(value, items[index], key)
        return type(node)(items)
    fields = init_fields(type(node))
    require(head in fields, full_key, value,
            f"unknown key; {describe(node, prefix)} takes " + ", ".join(fields))
    current = getattr(node, head)
    if rest and current is None:       # an unset table (``X | None``): set keys of a new one
        table = _unset_table(typing.get_type_hints(type(node)).get(head, typing.Any))
        current = table[0]() if table is not None and table[1] == "" else None
    if rest:
        new = _descend(current, rest, value, key, full_key)
    else:
        new = convert_field(type(node), fields[head], value, current, key)
    return dataclasses.replace(node, **{head: new})


def _descend(child, rest: list[str], value, key: str, full_key: str):
    require(dataclasses.is_dataclass(child) or isinstance(child, (list, tuple)), full_key, value,
            f"unknown key; {key} is a single value, set it whole: {key}=...")
    return set_path(child, rest, value, key, full_key)


def _list_index(items, text: str, list_key: str, full_key: str, value) -> int:
    """The item ``text`` names in ``items``; the error names the whole override key."""
    count = len(items)
    if count == 0:
        allowed = f"{list_key} is empty, so no index exists"
    else:
        indices = "0" if count == 1 else f"0 to {count - 1}"
        allowed = f"{list_key} has {count} item{'s' * (count > 1)}, so the index must be {indices}"
    require(text.isdigit() and int(text) < count, full_key, value, f"unknown key; {allowed}")
    return int(text)


# --- tables: TOML tables to dataclasses ---------------------------------------------------------


# --- values: TOML values to what a field holds ----------------------------------------------------


# --- scenes built in Python: the same checks as a scene file's values ----------------------------


# --- writing a scene back out as TOML -----------------------------------------------------------

def scene_to_toml(scene: Scene, only_changes: bool = False) -> str:
    """The scene as a TOML scene file that ``load_scene`` reads back to the same scene.

    ``only_changes`` leaves out every key that has its default value, but for the name and the
    step: a file that gives no dt gets one chosen from its springs (step_size.py), so the step
    the scene ran with is always written.
    """
    defaults = Scene() if only_changes else None
    tables = [name for name in init_fields(Scene) if name not in TYPED_LISTS
              and isinstance(getattr(scene, name), list)
              and _unset_table(typing.get_type_hints(Scene).get(name)) is not None]
    lines = [f"{name} = {toml_value(getattr(scene, name))}"
             for name in init_fields(Scene) if name not in TYPED_LISTS and name not in tables
             and getattr(scene, name) is not None   # unset (no wind): TOML has no null
             and (name in ("name", "dt") or not _is_default(scene, defaults, name))]
    for list_name, (_, registry) in TYPED_LISTS.items():
        for item in getattr(scene, list_name):
            kind = type_name(item, registry)
            lines += ["", f"[[{list_name}]]", f"type = {toml_value(kind)}"]
            lines += _table_lines(item, list_name, registry[kind]() if only_changes else None)
    for list_name in tables:   # arrays of tables without a type: [[attachments]]
        for item in getattr(scene, list_name):
            lines += ["", f"[[{list_name}]]"]
            lines += _table_lines(item, list_name,
                                  _default_instance(type(item)) if only_changes else None)
    return "\n".join(lines) + "\n"


def _table_lines(node, prefix: str, defaults=None) -> list[str]:
    """Plain keys first, then a ``[prefix.name]`` sub-table per dataclass field and a
    ``[[prefix.name]]`` table per item of a list of dataclasses (TOML wants that order).
    Keys equal to those of ``defaults`` (an instance, or None to keep every key) are left out."""
    lines, tables = [], []
    for name in init_fields(type(node)):
        value, key = getattr(node, name), f"{prefix}.{name}"
        if value is None or _is_default(node, defaults, name):
            continue   # None: unset, which TOML (no null) says by leaving the key out
        if dataclasses.is_dataclass(value):
            inner = _table_lines(value, key, getattr(defaults, name, None))
            tables += [f"[{key}]"] + inner
        elif is_table_list(value):
            for item in value:
                item_defaults = _default_instance(type(item)) if defaults is not None else None
                tables += [f"[[{key}]]"] + _table_lines(item, key, item_defaults)
        else:
            lines.append(f"{name} = {toml_value(value)}")
    return lines + tables


def _is_default(node, defaults, name: str) -> bool:
    if defaults is None:
        return False
    value, default = getattr(node, name), getattr(defaults, name)
    try:
        return bool(value == default) and type(value) is type(default)
    except ValueError:                      # arrays compare elementwise
        return bool(np.array_equal(value, default))


def _default_instance(cls):
    """``cls()`` where every field has a default; None (keep every key) otherwise."""
    try:
        return cls()
    except TypeError:
        return None


def toml_value(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return "true" if value else "false"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return repr(float(value))   # repr round-trips exactly and is valid TOML (1e-05, inf)
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, np.ndarray):
        return toml_value(value.tolist())
    if dataclasses.is_dataclass(value):
        value = {name: getattr(value, name) for name in init_fields(type(value))}
    if isinstance(value, dict):
        return "{" + ", ".join(f"{name} = {toml_value(item)}" for name, item in value.items()) + "}"
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(toml_value(item) for item in value) + "]"
    raise SceneError("scene", value, "holds a value that a TOML file cannot say")


def type_name(item, registry: dict) -> str:
    """The registry name of a body or terrain (the first entry that is exactly its class)."""
    for name, factory in registry.items():
        if factory is type(item):
            return name
    raise SceneError("scene", type(item).__name__,
                     "is not a registered type: " + ", ".join(registry))


# --- small helpers ------------------------------------------------------------------------------


# --- what a scene file accepts, for the documentation ---------------------------------------------

@dataclasses.dataclass(frozen=True)
class SceneKey:
    """One key a scene file accepts. ``path`` is the key as ``--set`` takes it, with ``N`` where
    a list index goes (``bodies.N.structural.ks``); ``owner`` is the body or terrain type it
    belongs to (``"scene"`` for the top level); ``kind`` says what value it holds."""

    owner: str
    path: str
    kind: str
    default: object


def scene_keys() -> list[SceneKey]:
    """Every key the readers above accept, found the way they find them (a table's keys are its
    dataclass's fields, ``TYPED_LISTS`` says which types a list holds), so that the generated
    scene-file reference lists exactly what a scene file may say."""
    keys = _table_keys(Scene(), "", "scene")
    for list_name, (_, registry) in TYPED_LISTS.items():
        for kind, factory in registry.items():
            keys.append(SceneKey(kind, f"{list_name}.N.type", "string", kind))
            keys += _table_keys(factory(), f"{list_name}.N", kind)
    return keys


def _table_keys(node, prefix: str, owner: str) -> list[SceneKey]:
    hints = typing.get_type_hints(type(node))
    keys = []
    for name in init_fields(type(node)):
        value, path = getattr(node, name), join_key(prefix, name)
        if type(node) is Scene and name in TYPED_LISTS:
            keys.append(SceneKey(owner, path, "array of tables, each with a type", []))
            continue
        annotation = hints.get(name, typing.Any)
        keys.append(SceneKey(owner, path, _kind_text(annotation, value), value))
        if dataclasses.is_dataclass(value):
            keys += _table_keys(value, path, owner)
        elif is_table_list(value):
            keys += _table_keys(value[0], f"{path}.N", owner)
        elif (table := _unset_table(annotation)) is not None:   # `X | None` or `list[X]`
            keys += _table_keys(_with_required_unset(table[0]), path + table[1], owner)
    return keys


def _with_required_unset(table):
    """An instance of a table's dataclass with its required keys (a keyframe's ``time``) None,
    which the reference shows as having no default."""
    required = {name: None for name, field in init_fields(table).items()
                if field.default is dataclasses.MISSING
                and field.default_factory is dataclasses.MISSING}
    return table(**required)


def _unset_table(annotation):
    """(the dataclass, the key suffix) of a field that holds a table but is unset by default:
    ``X | None`` (``""``) or ``list[X]`` (``".N"``), so that the reference lists its keys."""
    annotation = strip_optional(annotation)
    if dataclasses.is_dataclass(annotation):
        return annotation, ""
    arguments = typing.get_args(annotation)
    if typing.get_origin(annotation) is list and arguments and dataclasses.is_dataclass(
            arguments[0]):
        return arguments[0], ".N"
    return None


def _kind_text(annotation, default) -> str:
    """What ``convert`` takes for a field of this annotation and default, in words."""
    annotation = strip_optional(annotation)
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return " or ".join(_kind_text(kind, default) for kind in typing.get_args(annotation))
    if dataclasses.is_dataclass(default) or dataclasses.is_dataclass(annotation):
        return "table"
    names = {bool: "boolean", int: "whole number", float: "number", str: "string"}
    if annotation in names:
        return names[annotation]
    if annotation is np.ndarray:
        return "array"
    if annotation in (tuple, list) or typing.get_origin(annotation) in (tuple, list):
        if is_table_list(default) or _unset_table(annotation) is not None:
            return "array of tables"
        if isinstance(default, (tuple, list)) and default and all(
                isinstance(item, float) for item in default):
            return f"array of {len(default)} numbers"
        if isinstance(default, (tuple, list)) and all(is_integer(item) for item in default):
            return "array of whole numbers"
        return "array"
    return "value"
