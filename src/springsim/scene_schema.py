"""What a scene file accepts: every key, with the body or terrain type it belongs to, what
value it holds and its default, found the way the readers find them (for the generated
scene-file reference, docs/hooks/reference.py); and ``unset_table``, which tells the readers and
the writer that a field left unset by default holds a table.
"""
import dataclasses
import types
import typing

import numpy as np

from .scene import Scene
from .scene_values import (TYPED_LISTS, init_fields, is_integer, is_table_list, join_key,
                           strip_optional)


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
    """Every key the readers accept (scenefile.py, scene_overrides.py), found the way they find them (a table's keys are its
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
        elif (table := unset_table(annotation)) is not None:   # `X | None` or `list[X]`
            keys += _table_keys(_with_required_unset(table[0]), path + table[1], owner)
    return keys


def _with_required_unset(table):
    """An instance of a table's dataclass with its required keys (a keyframe's ``time``) None,
    which the reference shows as having no default."""
    required = {name: None for name, field in init_fields(table).items()
                if field.default is dataclasses.MISSING
                and field.default_factory is dataclasses.MISSING}
    return table(**required)


def unset_table(annotation):
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
        if is_table_list(default) or unset_table(annotation) is not None:
            return "array of tables"
        if isinstance(default, (tuple, list)) and default and all(
                isinstance(item, float) for item in default):
            return f"array of {len(default)} numbers"
        if isinstance(default, (tuple, list)) and all(is_integer(item) for item in default):
            return "array of whole numbers"
        return "array"
    return "value"
