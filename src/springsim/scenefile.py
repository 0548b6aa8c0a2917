"""Loading scenes: built-in names and TOML files (placeholder until the TOML loader lands)."""
from .presets import preset


def load_scene(name_or_path, overrides=()):
    return preset(str(name_or_path))
