"""A scene written back out as a TOML scene file, which scenefile.load_scene reads back to the
same scene (`springsim scenes`, checkpoints, recordings and fits write scenes this way).
"""
import dataclasses
import json
import numbers
import typing

import numpy as np

from .errors import SceneError
from .scene import Scene
from .scene_schema import unset_table
from .scene_values import TYPED_LISTS, init_fields, is_table_list


def scene_to_toml(scene: Scene, only_changes: bool = False) -> str:
    """The scene as a TOML scene file that ``load_scene`` reads back to the same scene.

    ``only_changes`` leaves out every key that has its default value, but for the name and the
    step: a file that gives no dt gets one chosen from its springs (step_size.py), so the step
    the scene ran with is always written.
    """
    defaults = Scene() if only_changes else None
    tables = [name for name in init_fields(Scene) if name not in TYPED_LISTS
              and isinstance(getattr(scene, name), list)
              and unset_table(typing.get_type_hints(Scene).get(name)) is not None]
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
