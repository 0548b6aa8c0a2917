"""Scene values: what a dataclass field of a scene holds, from a TOML value, checked.

The mapping is generic over the dataclasses (scenefile.py's docstring describes it for scene
files): a table's keys are its dataclass's fields, a field's annotation (or, for a bare
``tuple`` or ``list``, its default) says what it holds, and a field whose metadata says
``typed_list`` holds tables each with a ``type`` from ``TYPED_LISTS``. A scene built in Python
is checked the same way (``check_values``, called by ``Scene.validate``). Nothing here knows the
Scene class or the built-in scenes, so scene.py imports it without a cycle.
"""
import dataclasses
import math
import types
import typing
from dataclasses import MISSING

import numpy as np

from .bodies.balls import Balls
from .bodies.cloth import Cloth
from .bodies.cube import Cube
from .bodies.mesh import MeshBody
from .errors import SceneError, require
from .terms import FORCE_TYPES
from .terrains import TERRAIN_TYPES


BODY_TYPES = {"cube": Cube, "cloth": Cloth, "balls": Balls, "mesh": MeshBody}


# Scene fields that hold a list of tables, each with a ``type`` chosen from a registry.
TYPED_LISTS = {"bodies": ("body", BODY_TYPES), "terrains": ("terrain", TERRAIN_TYPES),
               "forces": ("force", FORCE_TYPES)}


def merge_table(base, table, prefix: str):
    """A copy of the dataclass ``base`` with the keys of ``table`` replaced, each checked."""
    fields = init_fields(type(base))
    require(isinstance(table, dict), prefix or "scene", table,
            "must be a table with the keys " + ", ".join(fields))
    for name in table:
        require(name in fields, join_key(prefix, name), table[name],
                f"unknown key; {describe(base, prefix)} takes " + ", ".join(fields))
    changes = {name: convert_field(type(base), fields[name], value, getattr(base, name),
                                   join_key(prefix, name))
               for name, value in table.items()}
    return dataclasses.replace(base, **changes)


def new_dataclass(cls, table, key: str):
    """A ``cls`` from a table alone: the fields the table does not give keep their defaults."""
    fields = init_fields(cls)
    require(isinstance(table, dict), key, table, "must be a table with the keys "
            + ", ".join(fields))
    for name in table:
        require(name in fields, join_key(key, name), table[name],
                f"unknown key; {key} takes " + ", ".join(fields))
    missing = [name for name, field in fields.items()
               if name not in table and _default_of(field) is MISSING]
    require(not missing, key, table, "needs the keys " + ", ".join(missing))
    return cls(**{name: convert_field(cls, fields[name], value, MISSING, join_key(key, name))
                  for name, value in table.items()})


def typed_item(value, list_name: str, current, key: str):
    """One body or terrain: a table with a ``type`` makes a new one, one without edits
    ``current``."""
    label, registry = TYPED_LISTS[list_name]
    require(isinstance(value, dict), key, value, f"must be a table describing a {label}")
    if "type" not in value and current is not None:
        return merge_table(current, value, key)
    kind = value.get("type")
    require(isinstance(kind, str) and kind in registry, f"{key}.type", kind,
            f"a {label} type must be one of " + ", ".join(registry))
    rest = {name: item for name, item in value.items() if name != "type"}
    return merge_table(registry[kind](), rest, key)


def convert_field(owner: type, field: dataclasses.Field, value, current, key: str):
    if field.name in TYPED_LISTS and field.metadata.get("typed_list"):
        require(isinstance(value, list), key, value,
                f"must be a list of tables ([[{field.name}]]), each with a type")
        return [typed_item(item, field.name, None, f"{key}.{i}") for i, item in enumerate(value)]
    annotation = typing.get_type_hints(owner).get(field.name, typing.Any)
    return convert(value, annotation, current, _default_of(field), key)


def convert(value, annotation, current, default, key: str):
    """``value`` (from TOML) as the value of a field annotated ``annotation``.

    ``current`` is the field's present value (a dataclass there is edited, not replaced) and
    ``default`` its default (which says what a bare ``tuple`` holds); either may be MISSING.
    """
    annotation = strip_optional(annotation)
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        return _convert_union(value, typing.get_args(annotation), current, default, key)
    if dataclasses.is_dataclass(current):
        return merge_table(current, value, key)
    if dataclasses.is_dataclass(annotation):
        return new_dataclass(annotation, value, key)
    if annotation in (bool, int, float, str):
        return _scalar(value, annotation, key)
    if annotation is np.ndarray:
        return np.asarray(_plain_list(value, key))
    if annotation in (tuple, list) or typing.get_origin(annotation) in (tuple, list):
        return _sequence(value, annotation, default, key)
    if annotation is typing.Any and current is not MISSING:
        return convert_like(value, current, key)
    require(_is_plain(value), key, value, "must be a number, boolean, string or array")
    return value


def convert_like(value, example, key: str):
    """``value`` as the same kind of value as ``example`` (an item of a list or tuple)."""
    if dataclasses.is_dataclass(example):
        return merge_table(example, value, key)
    if type(example) in (bool, int, float, str):
        return _scalar(value, type(example), key)
    if isinstance(example, (tuple, list)):
        return _like_default(value, example, type(example), key)
    return convert(value, typing.Any, MISSING, MISSING, key)


def _scalar(value, kind: type, key: str):
    if kind is bool:
        require(isinstance(value, bool), key, value, "must be true or false")
    elif kind is int:
        require(is_integer(value), key, value, "must be a whole number (no decimal point)")
    elif kind is float:
        require(_is_finite_number(value), key, value, "must be a finite number")
    else:
        require(isinstance(value, str), key, value, "must be a string (in quotes)")
    return kind(value)


def _convert_union(value, alternatives, current, default, key: str):
    """The alternative whose kind the value has (a string for ``str | list``); when several
    could take it, the first that accepts it."""
    fitting = [kind for kind in alternatives if _kind_fits(value, kind)]
    errors = []
    for kind in fitting or alternatives:
        try:
            return convert(value, kind, current, default, key)
        except SceneError as error:
            if len(fitting) == 1:
                raise
            errors.append(error.allowed)
    wanted = [errors[0]] + [text.removeprefix("must be ") for text in errors[1:]]
    raise SceneError(key, value, " or ".join(dict.fromkeys(wanted)))


def _kind_fits(value, kind) -> bool:
    kind = typing.get_origin(kind) or kind
    if kind in (tuple, list, np.ndarray):
        return isinstance(value, list)
    if kind in (int, float):
        return _is_number(value)
    if kind in (bool, str, dict):
        return isinstance(value, kind)
    if dataclasses.is_dataclass(kind):
        return isinstance(value, dict)
    return True


def _sequence(value, annotation, default, key: str):
    container = tuple if tuple in (annotation, typing.get_origin(annotation)) else list
    arguments = typing.get_args(annotation)
    require(isinstance(value, list), key, value, "must be an array")
    if arguments and arguments[-1] is not Ellipsis and container is tuple:   # tuple[float, float]
        require(len(value) == len(arguments), key, value,
                f"must be an array of {len(arguments)} values")
        return tuple(convert(item, kind, MISSING, MISSING, f"{key}.{i}")
                     for i, (item, kind) in enumerate(zip(value, arguments)))
    if arguments:                                                           # tuple[int, ...]
        return container(convert(item, arguments[0], MISSING, MISSING, f"{key}.{i}")
                         for i, item in enumerate(value))
    return _like_default(value, default, container, key)


def _like_default(value, default, container, key: str):
    """A bare ``tuple`` or ``list`` field: its default says what it holds (see the module doc)."""
    if not isinstance(default, (tuple, list)):
        return container(_plain_list(value, key))
    require(isinstance(value, list), key, value, "must be an array")
    if default and all(dataclasses.is_dataclass(item) for item in default):
        return container(new_dataclass(type(default[0]), item, f"{key}.{i}")
                         for i, item in enumerate(value))
    if default and all(isinstance(item, (tuple, list)) for item in default):
        return container(_like_default(row, default[0], type(default[0]), f"{key}.{i}")
                         for i, row in enumerate(value))
    if default and all(isinstance(item, float) for item in default):
        require(len(value) == len(default) and all(map(_is_finite_number, value)), key, value,
                f"must be an array of {len(default)} finite numbers")
        return container(float(item) for item in value)
    if all(is_integer(item) for item in default):
        require(all(map(is_integer, value)), key, value, "must be an array of whole numbers")
        return container(value)
    return container(_plain_list(value, key))


def _plain_list(value, key: str) -> list:
    require(isinstance(value, list) and all(_is_plain(item) for item in value), key, value,
            "must be an array of numbers, booleans or strings")
    return value


def check_values(node, prefix: str = "") -> None:
    """Check every value of a dataclass built in Python (a Scene, a body, a terrain) as a scene
    file's value is checked (its kind; a float finite), so that the Python API refuses what a
    scene file refuses, with the same one-line SceneError."""
    for name, field in init_fields(type(node)).items():
        value, key = getattr(node, name), join_key(prefix, name)
        if dataclasses.is_dataclass(value):
            check_values(value, key)
        elif is_table_list(value):
            for i, item in enumerate(value):
                check_values(item, f"{key}.{i}")
        elif value is not None or not _may_be_unset(type(node), field):
            _require_objects(type(node), field, value, key)
            convert_field(type(node), field, _as_toml(value), MISSING, key)


def _require_objects(owner: type, field: dataclasses.Field, value, key: str) -> None:
    """In Python, a field that a scene file fills with tables holds objects (a Keyframe, a Pin,
    a body): a dict there converts as a table would, and would then fail where its attributes
    are read, so it is refused here with the class it should be."""
    annotation = strip_optional(typing.get_type_hints(owner).get(field.name, typing.Any))
    if field.metadata.get("typed_list"):
        label, registry = TYPED_LISTS[field.name]
        wanted, items = f"a {label} object (" + ", ".join(sorted(
            {factory.__name__ for factory in registry.values()})) + ")", value
    elif dataclasses.is_dataclass(annotation):
        wanted, items = f"a {annotation.__name__} object", None
    elif typing.get_origin(annotation) in (list, tuple) and typing.get_args(annotation) and \
            dataclasses.is_dataclass(typing.get_args(annotation)[0]):
        wanted, items = f"a {typing.get_args(annotation)[0].__name__} object", value
    else:
        return
    listed = isinstance(items, (list, tuple))
    for name, item in (enumerate(items) if listed else [(None, value)]):
        require(dataclasses.is_dataclass(item) and not isinstance(item, type),
                key if name is None else f"{key}.{name}", item,
                f"must be {wanted}, not a {type(item).__name__}: in Python, build the object "
                "(a scene file's tables are made into them)")


def _as_toml(value):
    """A Python value as TOML would give it: sequences as lists, NumPy scalars as numbers,
    dataclasses as tables."""
    if isinstance(value, (tuple, list, np.ndarray)):
        return [_as_toml(item) for item in value]
    if isinstance(value, np.generic):
        return value.item()
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {name: _as_toml(getattr(value, name)) for name in init_fields(type(value))}
    return value


def init_fields(cls) -> dict:
    return {field.name: field for field in dataclasses.fields(cls) if field.init}


def describe(node, prefix: str) -> str:
    """How an error names a table: ``bodies.0 (cube)``, ``bodies.0.structural``, ``the scene``."""
    for _, registry in TYPED_LISTS.values():
        for name, factory in registry.items():
            if factory is type(node):
                return f"{prefix} ({name})"
    return prefix or "the scene"


def _default_of(field: dataclasses.Field):
    if field.default is not MISSING:
        return field.default
    if field.default_factory is not MISSING:
        return field.default_factory()
    return MISSING


def _may_be_unset(owner: type, field: dataclasses.Field) -> bool:
    """Whether the field is annotated ``X | None``: None then means unset (the default)."""
    annotation = typing.get_type_hints(owner).get(field.name, typing.Any)
    return (typing.get_origin(annotation) in (typing.Union, types.UnionType)
            and type(None) in typing.get_args(annotation))


def strip_optional(annotation):
    """``X | None`` is ``X`` here: TOML has no null."""
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        arguments = [a for a in typing.get_args(annotation) if a is not type(None)]
        if len(arguments) == 1:
            return arguments[0]
    return annotation


def is_table_list(value) -> bool:
    return (isinstance(value, (tuple, list)) and len(value) > 0
            and all(dataclasses.is_dataclass(item) for item in value))


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_finite_number(value) -> bool:
    try:
        return _is_number(value) and math.isfinite(value)
    except OverflowError:   # an int too large for a float (from Python, not TOML)
        return False


def is_integer(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_plain(value) -> bool:
    return isinstance(value, (int, float, str, bool))


def join_key(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name
