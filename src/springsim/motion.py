"""Prescribed rigid motion: where a terrain (or a pin) is at time t, and how fast it moves.

A ``Motion`` is a function of time alone, so a run, a copy of its state, a checkpoint and a
resumed run all see the same world (no state is kept between steps). It moves a thing placed in
the scene as

    x(t) = pivot + position(t) + R(t) (x_placed - pivot)

with either

- ``keyframes``: ``position`` (m) and a rotation (``rotation_degrees`` about ``rotation_axis``)
  at given times, interpolated ``linear``-ly or ``smooth``-ly (a C1 cubic through the keys:
  Catmull-Rom tangents inside, zero tangents at the first and last key, so that the motion
  starts and ends at rest). Before the first key and after the last the thing holds still.
  Rotations are interpolated as rotation vectors (axis times angle), so a turn about one axis
  turns at the interpolated angle exactly, through any number of turns (720 degrees is two);
- or a constant ``velocity`` (m/s) and ``angular_velocity`` (rad/s, a vector along the axis)
  about the ``pivot``, which moves with the velocity.

The ``pivot`` defaults to the moved thing's own anchor (a sphere's or bowl's centre, a plane's
point, a mesh terrain's position), so that a rotation alone turns it in place.

The velocity of a point y moving with the thing is  u(y) = c'(t) + w(t) x (y - c(t)), with
c(t) = pivot + position(t) its moving pivot and w the angular velocity (in the world frame).
The contact kernels use it to make restitution and friction relative to the surface.

In the kernels a motion is one row of ``motion_info`` (kind, first key, key count, pivot,
velocity, angular velocity) and its keys rows of ``motion_keys`` (time, position, rotation
vector); ``pose_into(info, keys, m, t, out)`` writes its pose at t (POSE numbers: see
``pose_into``). ``Motion.pose(t)`` is the NumPy twin the tests compare against.
"""
import math
from dataclasses import dataclass, field

import numpy as np

from ._jit import inline_kernel, kernel
from .errors import SceneError, is_finite, require

LINEAR, SMOOTH, VELOCITY = 0, 1, 2
INTERPOLATIONS = {"linear": LINEAR, "smooth": SMOOTH}
INFO = 12   # kind, first key, key count, pivot (3), velocity (3), angular velocity (3)
# m, m/s, rad/s: a component larger than this has a square, and so a length or a distance, that
# float64 cannot hold (the substeps, the contact and the poses all take lengths)
MAX_COMPONENT = 1e150
KEY = 7     # time, position (3), rotation vector (3)
POSE = 21   # R (9, row by row), c (3), pivot (3), c' (3), w (3)
# where each part of a pose starts (the kernels read them through pose_rotation and the like)
ROTATION, CENTRE, PIVOT, CENTRE_VELOCITY, ANGULAR_VELOCITY = 0, 9, 12, 15, 18
ROTATION_PART, CENTRE_PART, PIVOT_PART = slice(0, 9), slice(9, 12), slice(12, 15)
CENTRE_VELOCITY_PART, ANGULAR_VELOCITY_PART = slice(15, 18), slice(18, 21)


@dataclass
class Keyframe:
    """Where the moved thing is at ``time`` (s): displaced by ``position`` (m) and turned by
    ``rotation_degrees`` about ``rotation_axis`` (through the pivot)."""

    time: float
    position: tuple = (0.0, 0.0, 0.0)
    rotation_degrees: float = 0.0
    rotation_axis: tuple = (0.0, 1.0, 0.0)

    def rotation_vector(self) -> np.ndarray:
        axis = np.asarray(self.rotation_axis, float)
        return axis / np.linalg.norm(axis) * math.radians(self.rotation_degrees)


@dataclass
class Motion:
    """A prescribed rigid motion (module doc): ``keyframes``, or ``velocity`` and
    ``angular_velocity`` about ``pivot``."""

    keyframes: list[Keyframe] = field(default_factory=list)
    interpolation: str = "linear"
    velocity: tuple = (0.0, 0.0, 0.0)
    angular_velocity: tuple = (0.0, 0.0, 0.0)
    pivot: tuple | None = None   # m; unset: the owner's own anchor (a sphere's centre, ...)

    def validate(self, key: str) -> None:
        require(self.interpolation in INTERPOLATIONS, f"{key}.interpolation",
                self.interpolation, "must be " + " or ".join(f'"{n}"' for n in INTERPOLATIONS))
        for name in ("velocity", "angular_velocity", "pivot"):
            value = getattr(self, name)
            if value is None and name == "pivot":
                continue
            require(is_vector(value), f"{key}.{name}", value,
                    f"must be three finite numbers, each within +-{MAX_COMPONENT:g}")
        for name in ("velocity", "angular_velocity"):   # blame the one given with keyframes
            value = getattr(self, name)
            if self.keyframes and any(value):
                raise SceneError(f"{key}.{name}", value,
                                 "a motion is keyframes or a velocity and angular velocity, "
                                 "not both")
        previous = -math.inf
        for k, frame in enumerate(self.keyframes):
            here = f"{key}.keyframes.{k}"
            require(is_finite(frame.time), f"{here}.time", frame.time, "must be a finite number")
            require(frame.time > previous, f"{here}.time", frame.time,
                    f"keyframes must be in increasing time order, each later than the last "
                    f"({previous:g} s before it)")
            previous = frame.time
            require(is_vector(frame.position), f"{here}.position", frame.position,
                    f"must be three finite numbers (m), each within +-{MAX_COMPONENT:g}")
            require(is_finite(frame.rotation_degrees), f"{here}.rotation_degrees",
                    frame.rotation_degrees, "must be a finite number")
            require(np.shape(frame.rotation_axis) == (3,) and is_finite(frame.rotation_axis)
                    and np.linalg.norm(frame.rotation_axis) > 0, f"{here}.rotation_axis",
                    frame.rotation_axis, "must be three finite numbers, not all zero")

    def pivot_or(self, anchor) -> tuple:
        """The pivot: as given, or else ``anchor`` (what the moved thing turns about by
        default: a sphere's or bowl's centre, a plane's point, a mesh's position)."""
        return tuple(map(float, self.pivot if self.pivot is not None else anchor))

    def pack(self, first_key: int, anchor=(0.0, 0.0, 0.0)):
        """(its row of motion_info, its rows of motion_keys)."""
        kind = VELOCITY if not self.keyframes else INTERPOLATIONS[self.interpolation]
        info = [kind, first_key, len(self.keyframes), *self.pivot_or(anchor), *self.velocity,
                *self.angular_velocity]
        keys = np.array([[f.time, *f.position, *f.rotation_vector()] for f in self.keyframes],
                        float).reshape(-1, KEY)
        return np.asarray(info, float), keys

    def pose(self, t: float, anchor=(0.0, 0.0, 0.0)) -> np.ndarray:
        """The POSE numbers at time t (for tests, drawing and export)."""
        info, keys = self.pack(0, anchor)
        out = np.zeros(POSE)
        pose_into(info[None, :], keys if len(keys) else np.zeros((1, KEY)), 0, float(t), out)
        return out

    def place(self, points, t: float, anchor=(0.0, 0.0, 0.0)) -> np.ndarray:
        """``points`` (n, 3) as placed in the scene, moved to where they are at time t."""
        pose = self.pose(t, anchor)
        rotation = pose[:9].reshape(3, 3)
        return (np.asarray(points, float) - pose[PIVOT_PART]) @ rotation.T + pose[CENTRE_PART]


def is_vector(value) -> bool:
    """Three finite numbers whose lengths and differences float64 holds (MAX_COMPONENT)."""
    return (np.shape(value) == (3,) and is_finite(value)
            and bool(np.all(np.abs(np.asarray(value, float)) <= MAX_COMPONENT)))


@dataclass
class Path(Motion):
    """One point's own path (a pin's animation, bodies/pins.py): its ``displacements`` (F, 3)
    from where it starts at the sample ``times`` (F,), linear between them."""

    times: np.ndarray = None
    displacements: np.ndarray = None

    def pack(self, first_key: int, anchor=(0.0, 0.0, 0.0)):
        info = [LINEAR, first_key, len(self.times), *map(float, anchor), *[0.0] * 6]
        keys = np.column_stack([self.times, self.displacements, np.zeros((len(self.times), 3))])
        return np.asarray(info, float), keys


def pack_motions(motions) -> tuple[np.ndarray, np.ndarray]:
    """motion_info (M, INFO) and motion_keys (K, KEY) for a list of (Motion, anchor) (never
    empty arrays: one array type whatever the scene)."""
    info, keys, count = [np.zeros((0, INFO))], [np.zeros((0, KEY))], 0
    for motion, anchor in motions:
        row, own = motion.pack(count, anchor)
        info.append(row[None, :])
        keys.append(own)
        count += len(own)
    return np.concatenate(info), np.concatenate(keys + [np.zeros((1, KEY))])


@kernel
def segment(keys, first, count, t):
    """The key k (first <= k < first + count - 1) whose segment [t_k, t_k+1) holds t."""
    low, high = first, first + count - 2
    while low < high:   # bisection: the largest k with keys[k, 0] <= t
        middle = (low + high + 1) // 2
        if keys[middle, 0] <= t:
            low = middle
        else:
            high = middle - 1
    return low


@kernel
def tangent(keys, first, count, k, c):
    """The smooth interpolation's slope of column c at key k: Catmull-Rom inside (the slope of
    the chord between its neighbours), zero at the ends."""
    if k == first or k == first + count - 1:
        return 0.0
    return (keys[k + 1, c] - keys[k - 1, c]) / (keys[k + 1, 0] - keys[k - 1, 0])


@kernel
def interpolated(keys, first, count, kind, t, out):
    """out[0:6] = position and rotation vector at t, out[6:12] their time derivatives."""
    last = first + count - 1
    if count == 1 or t <= keys[first, 0] or t >= keys[last, 0]:
        k = first if (count == 1 or t <= keys[first, 0]) else last
        for c in range(6):
            out[c] = keys[k, 1 + c]
            out[6 + c] = 0.0
        return
    k = segment(keys, first, count, t)
    t0, t1 = keys[k, 0], keys[k + 1, 0]
    span = t1 - t0
    s = (t - t0) / span
    for c in range(6):
        p0, p1 = keys[k, 1 + c], keys[k + 1, 1 + c]
        if kind == LINEAR:
            out[c] = p0 + s * (p1 - p0)
            out[6 + c] = (p1 - p0) / span
        else:   # cubic Hermite with the tangents m0, m1 (per second)
            m0, m1 = tangent(keys, first, count, k, 1 + c), tangent(keys, first, count, k + 1, 1 + c)
            s2, s3 = s * s, s * s * s
            out[c] = ((2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * span * m0
                      + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * span * m1)
            out[6 + c] = ((6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * span * m0
                          + (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * span * m1) / span


@kernel
def pose_into(info, keys, m, t, out):
    """Motion m's pose at time t into out (POSE numbers): the rotation R (row by row), the moving
    pivot c = pivot + position, the pivot as placed, c' and the angular velocity w (world).
    A point placed at x is at c + R (x - pivot); one at y moves at c' + w x (y - c)."""
    kind = int(info[m, 0])
    moved = np.zeros(12)
    if kind == VELOCITY:
        for c in range(3):
            moved[c] = info[m, 6 + c] * t
            moved[3 + c] = info[m, 9 + c] * t
            moved[6 + c] = info[m, 6 + c]
            moved[9 + c] = info[m, 9 + c]
    else:
        interpolated(keys, int(info[m, 1]), int(info[m, 2]), kind, t, moved)
    r0, r1, r2 = moved[3], moved[4], moved[5]
    angle = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    # R = exp([r]) = I + a [r] + b [r]^2 (Rodrigues), and w = J(r) r', the left Jacobian
    # J = I + b [r] + d [r]^2, with a = sin/θ, b = (1 - cos)/θ², d = (θ - sin)/θ³; near θ = 0 their
    # series (the closed forms lose every digit there).
    if angle < 1e-4:
        theta2 = angle * angle
        a = 1.0 - theta2 / 6.0
        b = 0.5 - theta2 / 24.0
        d = 1.0 / 6.0 - theta2 / 120.0
    else:
        a = math.sin(angle) / angle
        b = (1.0 - math.cos(angle)) / (angle * angle)
        d = (angle - math.sin(angle)) / (angle * angle * angle)
    cross = np.array([[0.0, -r2, r1], [r2, 0.0, -r0], [-r1, r0, 0.0]])
    square = cross @ cross
    for i in range(3):
        for j in range(3):
            identity = 1.0 if i == j else 0.0
            out[3 * i + j] = identity + a * cross[i, j] + b * square[i, j]
    for i in range(3):
        out[9 + i] = info[m, 3 + i] + moved[i]
        out[12 + i] = info[m, 3 + i]
        out[15 + i] = moved[6 + i]
        w = moved[9 + i]
        for j in range(3):
            w += (b * cross[i, j] + d * square[i, j]) * moved[9 + j]
        out[18 + i] = w


@inline_kernel
def pose_rotation(p):
    """A pose's rotation R, row by row (nine numbers)."""
    r = ROTATION
    return (p[r], p[r + 1], p[r + 2], p[r + 3], p[r + 4], p[r + 5], p[r + 6], p[r + 7],
            p[r + 8])


@inline_kernel
def pose_vector(p, part):
    """The three numbers of a pose's ``part`` (CENTRE, PIVOT, CENTRE_VELOCITY, ...)."""
    return p[part], p[part + 1], p[part + 2]
