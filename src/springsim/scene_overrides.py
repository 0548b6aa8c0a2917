"""``--set key=value`` overrides: one value deep inside a scene replaced, checked as a scene
file's value is (scenefile.py's docstring says how keys address list items and what a value may
be). ``load_scene`` applies them after reading the scene; the sweeps apply their varied keys
the same way.
"""
import dataclasses
import tomllib
import typing

from .errors import require
from .scene import Scene
from .scene_schema import unset_table
from .scene_values import (TYPED_LISTS, convert_field, convert_like, describe, init_fields,
                           join_key, typed_item)


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
        table = unset_table(typing.get_type_hints(type(node)).get(head, typing.Any))
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
