"""The grid of a sweep: every combination of the varied values, each a complete run specification,
built and validated before anything runs.

``--vary KEY=V1,V2,...`` gives the values of one scene key (any key ``--set`` accepts, ``integrator``
and ``dt`` included); ``--vary KEY=START:STOP:COUNT`` gives COUNT evenly spaced values from START to
STOP (whole numbers when START and STOP are whole and the spacing is too). Runs are numbered in
the order of ``itertools.product`` over the ``--vary`` options as given, seeds innermost.

With ``seeds`` = N each combination runs N times, with seeds 0 .. N-1. A seed moves every free
(unpinned) particle's initial position by an amount drawn uniformly from [-a, a] in each
coordinate by ``np.random.default_rng(seed)``, with a = SEED_AMPLITUDE times the shortest spring
rest length of the model (SEED_AMPLITUDE times 0.1 m in a scene without springs): a 1 % nudge,
the same for the same seed on any machine.
"""
import hashlib
import itertools
import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from ..errors import require
from ..sampling import frame_step
from ..scenefile import (AutomaticStep, apply_override, load_scene, parse_value, scene_to_toml,
                         toml_value)

SEED_AMPLITUDE = 0.01   # share of the shortest rest length by which a seed moves a particle
MAX_RUNS = 100_000      # a grid larger than this is refused (it is most likely a typo)


@dataclass(frozen=True)
class Variation:
    key: str
    values: tuple


@dataclass(frozen=True)
class RunSpec:
    """Everything one run needs; ``run_id`` hashes the scene as simulated, the seed and the fps."""

    index: int
    settings: tuple          # ((key, value), ...) of the varied keys, in --vary order
    seed: int | None
    scene: object            # the scene.Scene to simulate, overrides applied and validated
    fps: float               # frames per simulated second sampled from the run
    save: bool               # keep the run's recording (NPZ)
    run_id: str


def parse_variation(text: str) -> Variation:
    """``KEY=V1,V2,...`` or ``KEY=START:STOP:COUNT``."""
    key, separator, raw = str(text).partition("=")
    key, raw = key.strip(), raw.strip()
    require(separator == "=" and key and raw, "--vary", text,
            "must be KEY=V1,V2,... or KEY=START:STOP:COUNT, for example "
            "bodies.0.structural.ks=1000,2000 or drag=0:1:5")
    items = split_top_level(raw, ",")
    parts = split_top_level(raw, ":")
    if len(items) == 1 and len(parts) == 3:
        return Variation(key, evenly_spaced(key, *parts))
    require(all(item.strip() for item in items), key, raw, "has an empty value between commas")
    return Variation(key, tuple(parse_value(item.strip()) for item in items))


def evenly_spaced(key: str, start_text: str, stop_text: str, count_text: str) -> tuple:
    start, stop, count = (parse_value(part.strip()) for part in (start_text, stop_text, count_text))
    allowed = "START:STOP:COUNT needs two finite numbers and a whole COUNT"
    require(all(_is_finite_number(value) for value in (start, stop)), key,
            f"{start_text}:{stop_text}:{count_text}", allowed)
    require(isinstance(count, int) and not isinstance(count, bool) and 1 <= count <= MAX_RUNS,
            key, count_text, f"COUNT must be a whole number from 1 to {MAX_RUNS}")
    values = np.linspace(start, stop, count)
    whole = all(isinstance(value, int) for value in (start, stop))
    if whole and np.all(values == np.round(values)):
        return tuple(int(value) for value in np.round(values))
    return tuple(float(value) for value in values)


def build_grid(scene: str, variations, *, overrides=(), seeds: int | None = None,
               fps: float = 60.0, save: bool = False) -> list[RunSpec]:
    """Every run of the sweep, each scene built and validated (a bad key or value raises the
    SceneError of the first combination that has it)."""
    keys = [variation.key for variation in variations]
    duplicates = sorted({key for key in keys if keys.count(key) > 1})
    require(not duplicates, "--vary", ", ".join(duplicates), "each key may be varied only once")
    require(seeds is None or (isinstance(seeds, int) and not isinstance(seeds, bool)
                              and seeds >= 1), "--seeds", seeds, "must be a whole number >= 1")
    require(math.isfinite(fps) and fps > 0, "--fps", fps, "must be > 0 frames per simulated second")
    seed_values = list(range(seeds)) if seeds else [None]
    total = math.prod(len(variation.values) for variation in variations) * len(seed_values)
    require(total <= MAX_RUNS, "--vary", " ".join(f"{key}=({len(v.values)} values)"
                                                  for key, v in zip(keys, variations)),
            f"makes {total} runs; a sweep may have at most {MAX_RUNS}")
    with warnings.catch_warnings(record=True) as said:   # said after the grid is known good
        warnings.simplefilter("always")
        base = load_scene(scene, overrides)
    specs = []
    for combination in itertools.product(*(variation.values for variation in variations)):
        settings = tuple(zip(keys, combination))
        varied = base
        for key, value in settings:
            varied = apply_override(varied, f"{key}={toml_value(value)}")
        # a dt that is a frame's step written short is that step, as `run` and `fit` read it
        # (sampling.frame_step): a saved run is then a take `fit` accepts with the same dt
        varied = replace(varied, dt=frame_step(varied.dt, fps))
        varied.validate()
        for seed in seed_values:
            specs.append(RunSpec(index=len(specs), settings=settings, seed=seed, scene=varied,
                                 fps=float(fps), save=save, run_id=run_id(varied, seed, fps)))
    for warning in said:
        if not (issubclass(warning.category, AutomaticStep) and "dt" in keys):
            warnings.warn_explicit(warning.message, warning.category, warning.filename,
                                   warning.lineno)
    return specs


def run_id(scene, seed: int | None, fps: float) -> str:
    """A short hash of what a run simulates and samples: equal ids, equal results."""
    text = f"{scene_to_toml(scene)}\nseed = {seed}\nfps = {float(fps)!r}\n"
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def perturb(simulation, seed: int | None) -> None:
    """Move the free particles' initial positions by the seed's nudge (module doc)."""
    if seed is None:
        return
    model = simulation.model
    rest = model.arrays.rest_length
    amplitude = SEED_AMPLITUDE * (float(rest.min()) if rest.size else 0.1)
    offsets = np.random.default_rng(seed).uniform(-amplitude, amplitude,
                                                  simulation.positions.shape)
    offsets[model.pinned] = 0.0
    simulation.state.positions += offsets


def split_top_level(text: str, separator: str) -> list[str]:
    """``text`` split at ``separator`` outside brackets, braces and quotes, so that an array
    value (``[0, -1.62, 0]``) stays whole."""
    parts, depth, quote, current = [], 0, None, []
    for character in text:
        if quote:
            quote = None if character == quote else quote
        elif character in "\"'":
            quote = character
        elif character in "[{":
            depth += 1
        elif character in "]}":
            depth -= 1
        elif character == separator and depth == 0:
            parts.append("".join(current))
            current = []
            continue
        current.append(character)
    parts.append("".join(current))
    return parts


def _is_finite_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)

