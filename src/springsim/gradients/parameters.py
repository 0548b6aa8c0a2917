"""What a gradient can be taken with respect to: named parameters, each of which knows its value,
how to set it, and its gradient from the adjoint's per-spring and per-particle cotangents.

Two kinds, an open set (``parameter`` tries each kind in PARAMETER_KINDS):

- ``SceneValue``: any number (or vector of numbers) of the scene, by its dotted key as ``--set``
  writes it: ``bodies.0.structural.ks``, ``gravity``, ``drag``, ``bodies.0.particle_mass``,
  ``bodies.0.velocity``, ``bodies.0.edge_length``. How the model depends on it is found by
  building the model at value +- delta (model.build_model): the springs' ks, kd and rest
  lengths, the masses, drag, gravity, the wind's settings and keys, the soft pins' stiffness
  and damping and the initial state are linear in every such key, so the difference is exact
  to rounding (``wind.gusts.length`` enters the gust modes as its inverse: exact to delta^2,
  about 1e-8 of the value). A key that
  changes anything else of the model (a terrain, the lattice) is refused as not
  differentiable.
- ``ModelArray``: one of the model's own arrays, set on the built model: ``initial_positions``,
  ``initial_velocities`` (P, 3), ``masses`` (P,), ``rest_lengths``, ``spring_ks``, ``spring_kd``
  (S,), and ``bodies.N.stiffness_field``, a scale on each spring of body N (1: the scene's ks).
  Setting rest lengths does not move the initial positions, and setting initial positions does
  not change rest lengths (the model's, built from the scene's positions, stay).
  ``bodies.N.stiffness_regions.AXIS=CUT[,CUT...]`` is the same scale, one per region: the
  regions are the slabs between the cuts (m) along AXIS (x, y or z), a spring in the slab its
  midpoint lies in at the model's initial positions. ``bodies.0.stiffness_regions.x=0`` is two
  numbers: the springs of body 0 left of x = 0, and those right of it.
"""
import re
import dataclasses

import numpy as np

from ..errors import SceneError
from ..model import build_model
from ..spring_runs import build_spring_runs
from .physics import Physical

# the model arrays that the adjoint covers (Physical) and that a SceneValue may change
COVERED = {"inv_mass", "gravity", "drag", "rest_length", "spring_group", "group_ks", "group_kd",
           "spring_runs", "run_rest_length", "loose_springs", "terrain_friction",
           "terrain_restitution", "wind_settings", "wind_keys", "wind_modes", "pin_stiffness",
           "pin_damping", "attachment_stiffness", "attachment_damping", "body_friction",
           "body_restitution", "ball_restitution", "particle_restitution", "particle_friction"}
# The model's work space, which the kernels write while they run (model.py): not a parameter
WORK_SPACE = {"clock", "motion_pose"}
MAX_GROUPS = 2 ** 31 - 1   # spring_group is int32
# Physical's fields with a cotangent (physics.Cotangents), which a SceneValue's tangents cover
DIFFERENTIABLE = ("ks", "kd", "rest", "mass", "drag", "gravity", "friction", "restitution",
                  "wind_settings", "wind_keys", "wind_modes", "pin_stiffness", "pin_damping",
                  "attachment_stiffness", "attachment_damping", "body_friction",
                  "body_restitution", "ball_restitution", "particle_restitution",
                  "particle_friction")


def parameter(scene, name):
    """The parameter ``name`` names in ``scene``; one clear error if none does."""
    if not isinstance(name, str):
        raise SceneError("wrt", name, "must be a parameter name (a string)")
    for kind in PARAMETER_KINDS:
        found = kind.named(scene, name)
        if found is not None:
            return found
    raise SceneError("wrt", name, "names no parameter: give a numeric scene key "
                     "(bodies.0.structural.ks, gravity, drag, ...) or one of "
                     + ", ".join(ModelArray.NAMES) + ", bodies.N.stiffness_field, "
                     "bodies.N.stiffness_regions.AXIS=CUTS")


class SceneValue:
    stage = "scene"

    def __init__(self, key, value):
        self.key, self.name = key, key
        self.shape = np.shape(value)
        self.value = np.asarray(value, float)

    @classmethod
    def named(cls, scene, name):
        try:
            value = get_path(scene, name.split("."))
        except (AttributeError, IndexError, ValueError, TypeError):
            return None
        if isinstance(value, bool) or not (isinstance(value, float) or (
                isinstance(value, (tuple, list)) and value
                and all(isinstance(c, float) for c in value))):
            if isinstance(value, (int, bool, str)) or value is None:
                raise SceneError("wrt", name, f"is {value!r}, not a real number: it cannot be "
                                 "differentiated")
            return None
        return cls(name, value)

    def apply(self, scene, value):
        from ..scenefile import set_path

        value = np.asarray(value, float).reshape(self.shape)
        plain = float(value) if value.ndim == 0 else [float(c) for c in value]
        return set_path(scene, self.key.split("."), plain, "", self.key)

    def tangents(self, scene):
        """[(Physical difference, x0 difference, v0 difference) per component], d/d value."""
        base = self.value.ravel()
        out = []
        for j in range(base.size):
            delta = 1e-4 * max(abs(base[j]), 1e-3)
            built, taken = [], []
            for sign in (1.0, -1.0):
                value = base.copy()
                value[j] += sign * delta
                taken.append(value[j])
                try:
                    changed = build_model(self.apply(scene, value))
                except SceneError as error:
                    raise SceneError("wrt", self.key, "cannot be differentiated at "
                                     f"{self.value.tolist()}: {error}") from None
                built.append(changed)
            # the two fresh models, not the run's, whose kernels have written their work space
            check_covered(self.key, built[0], built[1])
            span = taken[0] - taken[1]   # the step the values took, rounding included
            plus, minus = Physical.of(built[0]), Physical.of(built[1])
            out.append(tuple((plus.differentiable(name) - minus.differentiable(name)) / span
                             for name in DIFFERENTIABLE)
                       + ((built[0].initial_positions - built[1].initial_positions) / span,
                          (built[0].initial_velocities - built[1].initial_velocities) / span))
        return out

    def gradient(self, scene, model, result):
        bars = tuple(getattr(result.bar, name) for name in DIFFERENTIABLE) + (result.x0_bar,
                                                                               result.v0_bar)
        grad = [sum(float(np.sum(b * t)) for b, t in zip(bars, tangent))
                for tangent in self.tangents(scene)]
        return float(grad[0]) if self.shape == () else np.array(grad).reshape(self.shape)


def check_covered(key, model, changed):
    """Refuse a key that changes a model array the adjoint does not cover."""
    for field in model.arrays._fields:
        if field in COVERED or field in WORK_SPACE:
            continue
        if not same_values(getattr(model.arrays, field), getattr(changed.arrays, field)):
            raise SceneError("wrt", key, f"is not differentiable: it changes the model's "
                             f"{field}, which the gradient does not follow")
    if not np.array_equal(model.arrays.springs, changed.arrays.springs) or \
            not np.array_equal(model.pinned, changed.pinned):
        raise SceneError("wrt", key, "is not differentiable: it changes the springs or pins")


def same_values(old, new) -> bool:
    """Whether two model fields hold the same numbers (the terms' tables field by field)."""
    if isinstance(old, tuple):
        return (isinstance(new, tuple) and len(old) == len(new)
                and all(same_values(a, b) for a, b in zip(old, new)))
    return np.shape(old) == np.shape(new) and np.array_equal(old, new, equal_nan=True)


def get_path(node, parts):
    for part in parts:
        if isinstance(node, (list, tuple)):
            node = node[int(part)]
        elif dataclasses.is_dataclass(node):
            if part not in {f.name for f in dataclasses.fields(node)}:
                raise AttributeError(part)
            node = getattr(node, part)
        else:
            raise TypeError(part)
    return node


class ModelArray:
    """One of the model's own arrays (module doc); ``apply`` returns (model, state changes)."""

    NAMES = ("initial_positions", "initial_velocities", "masses", "rest_lengths", "spring_ks",
             "spring_kd")

    def __init__(self, name, kind, body=None):
        self.name, self.kind, self.body = name, kind, body

    @classmethod
    def named(cls, scene, name):
        parts = name.split(".")
        if name in cls.NAMES:
            return cls(name, name)
        regions = re.fullmatch(r"bodies\.(\d+)\.stiffness_regions\.([xyz])=(.+)", name)
        if regions:
            body = int(regions.group(1))
            if body >= len(scene.bodies):
                raise SceneError("wrt", name, f"names no body: the scene has bodies 0 to "
                                 f"{len(scene.bodies) - 1}")
            try:
                cuts = np.array(sorted(float(c) for c in regions.group(3).split(",")))
            except ValueError:
                cuts = np.array([np.nan])
            if not np.all(np.isfinite(cuts)):
                raise SceneError("wrt", name, "must end in AXIS=CUT[,CUT...], the cuts numbers "
                                 "(m): bodies.0.stiffness_regions.x=0")
            found = cls(name, "stiffness_regions", body)
            found.axis, found.cuts = "xyz".index(regions.group(2)), cuts
            return found
        if len(parts) == 3 and parts[0] == "bodies" and parts[2] == "stiffness_field":
            if not (parts[1].isdigit() and int(parts[1]) < len(scene.bodies)):
                raise SceneError("wrt", name, f"names no body: the scene has bodies 0 to "
                                 f"{len(scene.bodies) - 1}")
            return cls(name, "stiffness_field", int(parts[1]))
        return None

    stage = "model"

    def body_springs(self, model):
        body = model.bodies[self.body]
        first = model.arrays.springs[:, 0].astype(np.int64)
        return (first >= body.start) & (first < body.stop)

    def read(self, model):
        arrays = model.arrays
        if self.kind == "initial_positions":
            return model.initial_positions.copy()
        if self.kind == "initial_velocities":
            return model.initial_velocities.copy()
        if self.kind == "masses":
            return model.mass.copy()
        if self.kind == "rest_lengths":
            return arrays.rest_length.copy()
        if self.kind == "spring_ks":
            return arrays.group_ks[arrays.spring_group].astype(float)
        if self.kind == "spring_kd":
            return arrays.group_kd[arrays.spring_group].astype(float)
        if self.kind == "stiffness_regions":
            return np.ones(len(self.cuts) + 1)
        return np.ones(int(self.body_springs(model).sum()))   # stiffness_field: the scene's

    def region_of_springs(self, model):
        """The region of each of the body's springs (stiffness_regions): the slab its midpoint
        lies in, at the model's initial positions."""
        springs = model.arrays.springs[self.body_springs(model)].astype(np.int64)
        x = model.initial_positions
        middle = 0.5 * (x[springs[:, 0], self.axis] + x[springs[:, 1], self.axis])
        return np.searchsorted(self.cuts, middle, side="right")

    def current(self, model):
        """The scale this parameter last set (``apply``), or the scene's: 1."""
        applied = getattr(self, "applied", None)
        return self.read(model) if applied is None else applied

    def apply(self, model, value):
        """The model with this array set to ``value`` (the initial state is the model's)."""
        value = np.asarray(value, float)
        self.applied = value.copy()
        arrays = model.arrays
        current = self.read(model)
        if value.shape != current.shape:
            raise SceneError(self.name, f"an array of shape {value.shape}",
                             f"must have shape {current.shape}")
        if self.kind == "initial_positions":
            return dataclasses.replace(model, initial_positions=value.copy())
        if self.kind == "initial_velocities":   # a pinned particle stays at rest (build_model)
            return dataclasses.replace(model, initial_velocities=np.where(
                model.pinned[:, None], 0.0, value))
        if self.kind == "masses":
            return dataclasses.replace(model, mass=value.copy(), arrays=arrays._replace(
                inv_mass=np.where(model.pinned, 0.0, 1.0 / value)))
        if self.kind == "rest_lengths":
            return dataclasses.replace(model, arrays=arrays._replace(
                rest_length=value.copy(),
                **build_spring_runs(arrays.springs, arrays.spring_group, value)))
        ks = arrays.group_ks[arrays.spring_group].astype(float)
        kd = arrays.group_kd[arrays.spring_group].astype(float)
        if self.kind == "spring_ks":
            ks = value
        elif self.kind == "spring_kd":
            kd = value
        elif self.kind == "stiffness_regions":
            ks = ks.copy()
            ks[self.body_springs(model)] *= value[self.region_of_springs(model)]
        else:
            ks = ks.copy()
            ks[self.body_springs(model)] *= value
        return regrouped(model, ks, kd)

    def gradient(self, scene, model, result):
        bar = result.bar
        if self.kind == "initial_positions":
            return result.x0_bar.copy()
        if self.kind == "initial_velocities":
            return result.v0_bar.copy()
        if self.kind == "masses":
            return bar.mass.copy()
        if self.kind == "rest_lengths":
            return bar.rest.copy()
        if self.kind == "spring_ks":
            return bar.ks.copy()
        if self.kind == "spring_kd":
            return bar.kd.copy()
        members = self.body_springs(model)
        ks = model.arrays.group_ks[model.arrays.spring_group].astype(float)
        # ks = scale times the scene's ks: d ks / d scale = ks / scale at the scale applied
        if self.kind == "stiffness_regions":
            regions = self.region_of_springs(model)
            per_spring = (bar.ks * ks)[members] / self.current(model)[regions]
            return np.bincount(regions, weights=per_spring, minlength=len(self.cuts) + 1)
        return (bar.ks * ks)[members] / self.current(model)


def regrouped(model, ks, kd):
    """The model with spring s given (ks[s], kd[s]): one parameter group per distinct pair."""
    arrays = model.arrays
    pairs, group = np.unique(np.stack([ks, kd], axis=1), axis=0, return_inverse=True)
    if len(pairs) > MAX_GROUPS:
        raise SceneError("spring stiffness", f"{len(pairs)} distinct (ks, kd) pairs",
                         f"must be at most {MAX_GROUPS} (the model's parameter groups)")
    group = group.ravel().astype(np.int32)
    return dataclasses.replace(model, arrays=arrays._replace(
        spring_group=group, group_ks=pairs[:, 0].copy(), group_kd=pairs[:, 1].copy(),
        **build_spring_runs(arrays.springs, group, arrays.rest_length)))


PARAMETER_KINDS = [ModelArray, SceneValue]
