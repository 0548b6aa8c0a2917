"""A scene as TOML text, from nested dicts and lists (Python's tomllib reads TOML but does not
write it, and springsim's own writer is not imported inside Blender).

Lists of tables named in ``TABLE_LISTS`` become ``[[array tables]]``; other lists of tables (motion
keyframes) an array of inline tables, one a line; floats are written with ``repr`` so that the
file holds every bit of the number Blender computed.
"""
TABLE_LISTS = ("bodies", "terrains", "pins")


def scene_text(scene: dict, comment: str = "") -> str:
    lines = [f"# {line}" for line in comment.splitlines()]
    _table(scene, [], lines)
    return "\n".join(lines) + "\n"


def _table(table: dict, path: list, lines: list) -> None:
    plain = {k: v for k, v in table.items() if not _is_table(v) and not _is_table_list(k, v)}
    for key, value in plain.items():
        lines.append(f"{key} = {value_text(value)}")
    for key, value in table.items():
        if _is_table(value):
            lines.append(f"[{'.'.join(path + [key])}]")
            _table(value, path + [key], lines)
    for key, value in table.items():
        if _is_table_list(key, value):
            for item in value:
                lines.append("")
                lines.append(f"[[{'.'.join(path + [key])}]]")
                _table(item, path + [key], lines)


def _is_table(value) -> bool:
    return isinstance(value, dict)


def _is_table_list(key, value) -> bool:
    return key in TABLE_LISTS and isinstance(value, list)


def value_text(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(float(value))
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {value_text(v)}" for k, v in value.items()) + "}"
    if value and all(isinstance(item, dict) for item in value):
        return "[\n" + "".join(f"  {value_text(item)},\n" for item in value) + "]"
    return "[" + ", ".join(value_text(item) for item in value) + "]"
