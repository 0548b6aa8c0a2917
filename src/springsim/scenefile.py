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

The mapping is generic over the dataclasses: a table's keys are its dataclass's fields, a nested
dataclass field is a sub-table (given keys replace those of the default, the rest are kept), and
the type of each value is read from the field's annotation, or from its default where the
annotation is a bare ``tuple``: a default of floats is a fixed-length vector (``gravity``), of
tuples a list of such vectors, of ints or empty a list of integers of any length (``pinned``).
Annotate ``tuple[float, ...]`` and the like to say otherwise. A new body kind needs one line in
``BODY_TYPES``; terrain kinds come from ``terrains.TERRAIN_TYPES``.

Overrides address list items by index: ``bodies.0.particles_per_edge=7``,
``terrains.0.friction=0.5``, ``bodies.0.structural.ks=3000``. Values are TOML values
(``1e-3``, ``true``, ``[0, -1.62, 0]``, ``{ks = 10, kd = 1}``); a bare word is a string.
"""
import dataclasses
import json
import math
import numbers
import tomllib
import types
import typing
from pathlib import Path

import numpy as np

from .bodies.cube import Cube
from .errors import SceneError, require
from .presets import PRESETS, preset
from .scene import Scene
from .terrains import TERRAIN_TYPES

BODY_TYPES = {"cube": Cube}

# Scene fields that hold a list of tables, each with a ``type`` chosen from a registry.
TYPED_LISTS = {"bodies": ("body", BODY_TYPES), "terrains": ("terrain", TERRAIN_TYPES)}


def load_scene(name_or_path, overrides=()) -> Scene:
    """A built-in scene or a TOML scene file, with ``"dotted.key=value"`` overrides, validated."""
    text = str(name_or_path)
    if text in PRESETS:
        scene = preset(text)
    elif text.endswith(".toml") or Path(text).is_file():
        scene = read_scene_file(Path(text))
    else:
        raise SceneError("scene", text, "must be a .toml scene file or one of "
                         + ", ".join(PRESETS))
    for override in overrides:
        scene = apply_override(scene, override)
    scene.validate()
    return scene


def read_scene_file(path: Path) -> Scene:
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SceneError("scene", str(path), "no such file; give a .toml scene file or one of "
                         + ", ".join(PRESETS)) from None
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError("scene", str(path), f"cannot be read ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise SceneError("scene", str(path), f"is not valid TOML: {error}") from None
    # A file that does not name its scene is named after itself (and so is its output).
    return scene_from_table({"name": path.stem, **table})


def scene_from_table(table: dict) -> Scene:
    """A Scene from a parsed TOML document; every key and value is checked."""
    return merge_table(Scene(), table, "")


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


# --- walking the dataclasses -------------------------------------------------------------------

def set_path(node, parts: list[str], value, prefix: str, full_key: str):
    """A copy of ``node`` (a dataclass or a typed list) with the value at ``parts`` replaced.

    ``prefix`` is the key of ``node``; errors about the path name the whole ``full_key``.
    """
    head, rest = parts[0], parts[1:]
    key = _join(prefix, head)
    if isinstance(node, list):
        index = _list_index(node, head, prefix, full_key, value)
        items = list(node)
        if rest:
            items[index] = set_path(items[index], rest, value, key, full_key)
        else:
            items[index] = typed_item(value, prefix, items[index], key)
        return items
    fields = init_fields(type(node))
    require(head in fields, full_key, value,
            f"unknown key; {describe(node, prefix)} takes " + ", ".join(fields))
    current = getattr(node, head)
    if not rest:
        new = convert_field(type(node), fields[head], value, current, key)
    elif dataclasses.is_dataclass(current) or _is_typed_list(node, head):
        new = set_path(current, rest, value, key, full_key)
    else:
        raise SceneError(full_key, value,
                         f"unknown key; {key} is a single value, set it whole: {key}=...")
    return dataclasses.replace(node, **{head: new})


def merge_table(base, table, prefix: str):
    """A copy of the dataclass ``base`` with the keys of ``table`` replaced, each checked."""
    require(isinstance(table, dict), prefix or "scene", table,
            "must be a table of keys: " + ", ".join(init_fields(type(base))))
    fields = init_fields(type(base))
    for name in table:
        require(name in fields, _join(prefix, name), table[name],
                f"unknown key; {describe(base, prefix)} takes " + ", ".join(fields))
    changes = {name: convert_field(type(base), fields[name], value, getattr(base, name),
                                   _join(prefix, name))
               for name, value in table.items()}
    return dataclasses.replace(base, **changes)


def convert_field(owner: type, field: dataclasses.Field, value, current, key: str):
    if owner is Scene and field.name in TYPED_LISTS:
        require(isinstance(value, list), key, value,
                f"must be a list of tables ([[{field.name}]]), each with a type")
        return [typed_item(item, field.name, None, f"{key}.{i}") for i, item in enumerate(value)]
    annotation = typing.get_type_hints(owner).get(field.name, typing.Any)
    return convert(value, annotation, current, _default_of(field), key)


def typed_item(value, list_name: str, current, key: str):
    """One body or terrain: a table with a ``type`` builds a new one, without it edits ``current``."""
    label, registry = TYPED_LISTS[list_name]
    require(isinstance(value, dict), key, value, f"must be a table describing a {label}")
    if "type" not in value and current is not None:
        return merge_table(current, value, key)
    kind = value.get("type")
    require(kind in registry, f"{key}.type", kind,
            f"a {label} type must be one of " + ", ".join(registry))
    rest = {name: item for name, item in value.items() if name != "type"}
    return merge_table(registry[kind](), rest, key)


def convert(value, annotation, current, default, key: str):
    """``value`` (from TOML) as the Python value a field of type ``annotation`` holds."""
    annotation = _strip_optional(annotation)
    origin = typing.get_origin(annotation)
    if dataclasses.is_dataclass(annotation) or dataclasses.is_dataclass(current):
        base = current if dataclasses.is_dataclass(current) else None
        if base is None:
            return _new_dataclass(annotation, value, key)
        return merge_table(base, value, key)
    if annotation is bool:
        require(isinstance(value, bool), key, value, "must be true or false")
        return value
    if annotation is int:
        require(_is_integer(value), key, value, "must be a whole number (no decimal point)")
        return int(value)
    if annotation is float:
        require(_is_number(value) and math.isfinite(value), key, value, "must be a finite number")
        return float(value)
    if annotation is str:
        require(isinstance(value, str), key, value, "must be a string (in quotes)")
        return value
    if annotation is np.ndarray:
        return _vector(value, None, float, key, np.asarray)
    if annotation in (tuple, list) or origin in (tuple, list):
        return _sequence(value, annotation, default, key)
    require(_is_plain(value), key, value, "must be a number, boolean, string or array")
    return value


def _sequence(value, annotation, default, key: str):
    container = tuple if tuple in (annotation, typing.get_origin(annotation)) else list
    arguments = typing.get_args(annotation)
    if arguments and arguments[-1] is not Ellipsis:        # tuple[float, float, float]
        require(isinstance(value, list) and len(value) == len(arguments), key, value,
                f"must be an array of {len(arguments)} values")
        return container(convert(item, kind, None, dataclasses.MISSING, f"{key}.{i}")
                         for i, (item, kind) in enumerate(zip(value, arguments)))
    if arguments:                                           # tuple[int, ...], list[float]
        require(isinstance(value, list), key, value, "must be an array")
        return container(convert(item, arguments[0], None, dataclasses.MISSING, f"{key}.{i}")
                         for i, item in enumerate(value))
    return _sequence_like_default(value, default, container, key)


def _sequence_like_default(value, default, container, key: str):
    """A bare ``tuple`` field: its default says what it holds (see the module docstring)."""
    if default is dataclasses.MISSING or default is None:
        require(isinstance(value, list) and all(_is_plain(item) for item in value), key, value,
                "must be an array")
        return container(value)
    default = tuple(default)
    if default and all(isinstance(item, (tuple, list)) for item in default):
        require(isinstance(value, list), key, value, "must be an array of arrays")
        return container(_sequence_like_default(row, default[0], tuple, f"{key}.{i}")
                         for i, row in enumerate(value))
    if default and all(isinstance(item, float) for item in default):
        return _vector(value, len(default), float, key, container)
    if all(_is_integer(item) for item in default):
        return _vector(value, None, int, key, container)
    require(isinstance(value, list) and all(_is_plain(item) for item in value), key, value,
            "must be an array")
    return container(value)


def _vector(value, length, kind, key: str, container):
    what = f"{length} " if length else ""
    noun = "whole numbers" if kind is int else "finite numbers"
    valid = _is_integer if kind is int else _is_finite_number
    require(isinstance(value, list) and (length is None or len(value) == length)
            and all(valid(item) for item in value), key, value,
            f"must be an array of {what}{noun}")
    return container(kind(item) for item in value)


def _new_dataclass(cls, value, key: str):
    """A dataclass with no default instance to start from: every field without a default is
    required."""
    require(isinstance(value, dict), key, value,
            "must be a table of keys: " + ", ".join(init_fields(cls)))
    fields = init_fields(cls)
    missing = [name for name, field in fields.items()
               if name not in value and _default_of(field) is dataclasses.MISSING]
    require(not missing, _join(key, missing[0] if missing else ""), None,
            "is required: give " + ", ".join(missing))
    for name in value:
        require(name in fields, _join(key, name), value[name],
                f"unknown key; {key} takes " + ", ".join(fields))
    return cls(**{name: convert(item, typing.get_type_hints(cls).get(name, typing.Any), None,
                                _default_of(fields[name]), _join(key, name))
                  for name, item in value.items()})


# --- writing a scene back out as TOML -----------------------------------------------------------

def scene_to_toml(scene: Scene) -> str:
    """The scene as a TOML scene file that ``load_scene`` reads back to the same scene."""
    lines = []
    for name, field in init_fields(Scene).items():
        if name not in TYPED_LISTS:
            lines.append(f"{name} = {toml_value(getattr(scene, name))}")
    for list_name, (label, registry) in TYPED_LISTS.items():
        for item in getattr(scene, list_name):
            lines += ["", f"[[{list_name}]]", f"type = {toml_value(type_name(item, registry))}"]
            lines += _table_lines(item, list_name)
    return "\n".join(lines) + "\n"


def _table_lines(node, prefix: str) -> list[str]:
    """Plain keys first, then a ``[prefix.name]`` sub-table per nested dataclass."""
    values = {name: getattr(node, name) for name in init_fields(type(node))}
    lines = [f"{name} = {toml_value(value)}" for name, value in values.items()
             if not dataclasses.is_dataclass(value)]
    for name, value in values.items():
        if dataclasses.is_dataclass(value):
            lines += [f"[{prefix}.{name}]"] + _table_lines(value, f"{prefix}.{name}")
    return lines


def toml_value(value) -> str:
    if isinstance(value, bool):
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
        return "{" + ", ".join(f"{name} = {toml_value(getattr(value, name))}"
                               for name in init_fields(type(value))) + "}"
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

def init_fields(cls) -> dict:
    return {field.name: field for field in dataclasses.fields(cls) if field.init}


def describe(node, prefix: str) -> str:
    for _, registry in TYPED_LISTS.values():
        for name, factory in registry.items():
            if factory is type(node):
                return f"{prefix} ({name})" if prefix else name
    return prefix or "a scene"


def _list_index(items: list, text: str, list_key: str, full_key: str, value) -> int:
    """The item ``text`` names in ``items``; the error names the whole override key."""
    count = len(items)
    if count == 0:
        allowed = f"{list_key} is empty, so no index exists"
    else:
        indices = "0" if count == 1 else f"0 to {count - 1}"
        allowed = f"{list_key} has {count} item{'s' * (count > 1)}, so the index must be {indices}"
    require(text.isdigit() and int(text) < count, full_key, value, f"unknown key; {allowed}")
    return int(text)


def _is_typed_list(node, name: str) -> bool:
    return isinstance(node, Scene) and name in TYPED_LISTS


def _default_of(field: dataclasses.Field):
    if field.default is not dataclasses.MISSING:
        return field.default
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return dataclasses.MISSING


def _strip_optional(annotation):
    """``X | None`` is ``X`` here: TOML has no null."""
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        arguments = [a for a in typing.get_args(annotation) if a is not type(None)]
        if len(arguments) == 1:
            return arguments[0]
    return annotation


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_finite_number(value) -> bool:
    return _is_number(value) and math.isfinite(value)


def _is_integer(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_plain(value) -> bool:
    return isinstance(value, (int, float, str, bool))


def _join(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name
