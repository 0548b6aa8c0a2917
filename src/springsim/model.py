"""The model: everything that stays fixed while simulating, built once from a scene.

Kernels receive ``model.arrays`` (a NamedTuple of arrays and numbers, which Numba compiles against);
the rest of the model (body slices, spring kinds, surfaces) serves output, rendering and tests.
"""
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .attachments import hold_attachments, pack_attachments
from .bodies.balls import collision_parameters
from .clock import SLOTS as CLOCK_SLOTS
from .collision.shapes.surfaces import surface_contact_arrays
from .spring_runs import PARTITION, build_spring_runs, checked_partition
from .springs import SpringKind
from .surfaces import Embedding
from .terms import TERMS
from .terrains import pack_terrains
from .wind import pack_wind, quads_both_ways
from .world_tables import pack_world


class ModelArrays(NamedTuple):
    inv_mass: np.ndarray         # (P,) 1/kg, zero for pinned particles
    radius: np.ndarray           # (P,) m, contact radius (zero for points)
    terrain_offset: np.ndarray   # (P,) m, kept between a particle and a terrain: its contact
                                 # radius, or how far a mesh body's surface reaches beyond it
    gravity: np.ndarray          # (3,) m/s^2
    drag: np.ndarray             # (P,) viscous drag coefficient c (N s/m): f = -c v
    springs: np.ndarray          # (S, 2) uint32 particle numbers (unsigned: no wrap-around checks)
    rest_length: np.ndarray      # (S,) m
    spring_group: np.ndarray     # (S,) int32, row of the group tables below (one per (ks, kd))
    group_ks: np.ndarray         # (G,) N/m
    group_kd: np.ndarray         # (G,) N s/m
    spring_runs: np.ndarray      # (R, 5) int64 first, offset, count, start, group (spring_runs.py)
    run_rest_length: np.ndarray  # (E,) m, the runs' rest lengths; negative at a hole
    loose_springs: np.ndarray    # (L,) uint32 numbers of the springs in no run
    spring_partition: int        # particles per partition of the force loop, at least
                                 # (spring_runs.py): PARTITION unless a Simulation asks
    terrain_kind: np.ndarray     # (T,) int64, the kind number (terrains/base.py)
    terrain_parameters: np.ndarray  # (T, K) each terrain's parameters, as its kind packs them
    terrain_data: np.ndarray     # (D,) the data the terrains share (a mesh's distance grid)
    terrain_restitution: np.ndarray
    terrain_friction: np.ndarray
    terrain_epsilon: np.ndarray
    # The world that moves (motion.py, world.py): each terrain's row of the motion table (-1:
    # still), the motions (the moving terrains', then the moving pins') and their keys, their
    # poses at the time last asked for (world.move_world), and the pins that move: particle,
    # motion row, and where the particle started (in the motion's frame at its placing)
    terrain_motion: np.ndarray   # (T,) int64
    # where each deforming terrain's block starts in terrain_data (-1: it keeps its shape),
    # refitted to the time by world.move_world (terrains/deforming_mesh.py)
    terrain_deforming: np.ndarray   # (T,) int64
    motion_info: np.ndarray      # (M, motion.INFO)
    motion_keys: np.ndarray      # (K, motion.KEY)
    motion_pose: np.ndarray      # (M, motion.POSE), written by the kernels
    pin_particles: np.ndarray    # (Q,) int64
    pin_motion: np.ndarray       # (Q,) int64
    pin_placed: np.ndarray       # (Q, 3) m
    pin_stiffness: np.ndarray    # (Q,) N/m, 0 for a hard pin
    pin_damping: np.ndarray      # (Q,) N s/m
    # the times of clock.py's slots (s): written by the integrators (Integrator.advance,
    # integrators/_steps.drive, world.start_step) and
    # read by the stages, which move the world to their own time (world.py); work space, like
    # motion_pose, which the model lends the kernels so that no kernel signature carries the time
    clock: np.ndarray            # (clock.SLOTS,)
    # Wind (wind.py): settings, velocity keys, gust modes, and the triangles it blows on
    wind_settings: np.ndarray    # (6,)
    wind_keys: np.ndarray        # (K, 4) time, velocity
    wind_modes: np.ndarray       # (G, 8)
    wind_triangles: np.ndarray   # (W, 3) int64 particle numbers
    wind_weights: np.ndarray     # (W,) the share of each triangle's force that acts (wind.py)
    # Ball contacts (collision/pipeline.py). A ball is a particle with radius > 0 (only Balls
    # bodies give radii); every other particle is a point.
    balls: np.ndarray = np.empty(0, np.int64)                 # (B,) particle numbers, ascending
    ball_slot: np.ndarray = np.empty(0, np.int64)             # (P,) row in the ball tables, or -1
    ball_restitution: np.ndarray = np.empty(0)                # (B,) ball-ball
    particle_restitution: np.ndarray = np.empty(0)            # (B,) ball-particle
    particle_friction: np.ndarray = np.empty(0)               # (B,) ball-particle Coulomb friction
    position_correction: np.ndarray = np.empty(0)             # (B,) share of a penetration removed
    # Sheets (bodies that are all surface: cloth): their triangles, which balls touch as surfaces
    # in implicit_euler's solve (collision/response/penalty.py), and each particle's triangles
    sheet_triangles: np.ndarray = np.empty((0, 3), np.int64)  # (T, 3) particle numbers
    triangle_start: np.ndarray = np.zeros(1, np.int64)        # (P + 1,) into particle_triangles
    particle_triangles: np.ndarray = np.empty(0, np.int64)    # (3T,) rows of sheet_triangles
    # Body-body contact of surfaces (collision/shapes/surfaces.py, collision/pipeline.py); empty
    # when no two surfaces can touch
    particle_body: np.ndarray = np.empty(0, np.int64)         # (P,) each particle's contact body:
                                                              # a connected piece of a body
    surface_points: np.ndarray = np.empty(0, np.int64)        # (Q,) particles on a surface
    surface_triangles: np.ndarray = np.empty((0, 3), np.int64)  # (T,) particle numbers
    surface_edges: np.ndarray = np.empty((0, 2), np.int64)    # (E,) the triangles' edges
    neighbour_start: np.ndarray = np.zeros(1, np.int64)       # (P + 1,) into neighbours
    neighbours: np.ndarray = np.empty(0, np.int64)            # particles joined by a surface edge
    body_thickness: np.ndarray = np.empty(0)                  # (B,) m
    body_self_collision: np.ndarray = np.empty(0, np.bool_)   # (B,)
    body_friction: np.ndarray = np.empty(0)                   # (B,) kinetic Coulomb coefficient
    body_static_friction: np.ndarray = np.empty(0)            # (B,)
    body_restitution: np.ndarray = np.empty(0)                # (B,)
    # One self-colliding sheet (collision/pair_lists/unfolded_sheet.py; empty otherwise): each
    # particle's ring edges, the boundary edges, the particles near them
    sheet_ring_start: np.ndarray = np.zeros(1, np.int64)      # (P + 1,) into sheet_ring_edges
    sheet_ring_edges: np.ndarray = np.empty((0, 2), np.int32)  # (R, 2) particle numbers
    sheet_boundary: np.ndarray = np.empty((0, 2), np.int64)   # (G, 2) directed along it
    sheet_near_boundary: np.ndarray = np.empty(0, np.int64)   # (N,) particles
    # Attachments (attachments.py): per bound particle, its stencil (the particle, then its
    # triangle's corners) and weights (1, -w_a, -w_b, -w_c), and its spring (0 N/m: hard)
    attachment_nodes: np.ndarray = np.empty((0, 4), np.int64)  # (A, 4) particle numbers
    attachment_weights: np.ndarray = np.empty((0, 4))          # (A, 4), summing to zero
    attachment_stiffness: np.ndarray = np.empty(0)             # (A,) N/m
    attachment_damping: np.ndarray = np.empty(0)               # (A,) N s/m
    # each term's own table of parameters, in terms.TERMS' order (terms/base.py): () for the
    # forces whose arrays are above
    term_tables: tuple = ()


@dataclass(frozen=True)
class BodySlice:
    """Where one body's particles lie in the model, and its surface triangles: global particle
    numbers, or rows of the embedded vertices when ``embedding`` is set (surfaces.py)."""

    name: str
    start: int
    stop: int
    surface: np.ndarray
    embedding: object = None   # surfaces.Embedding or None


@dataclass(frozen=True)
class Model:
    arrays: ModelArrays
    mass: np.ndarray             # (P,) kg
    pinned: np.ndarray           # (P,) bool
    spring_kind: np.ndarray      # (S,) int8 SpringKind
    bodies: tuple                # BodySlice per body
    initial_positions: np.ndarray
    initial_velocities: np.ndarray
    terrains: tuple
    scene_bodies: tuple          # the body descriptions the model was built from

    @property
    def particle_count(self) -> int:
        return len(self.mass)

    @property
    def springs(self) -> np.ndarray:
        return self.arrays.springs

    def spring_count(self, kind: SpringKind | None = None) -> int:
        if kind is None:
            return len(self.spring_kind)
        return int(np.count_nonzero(self.spring_kind == kind))


def build_model(scene, spring_partition: int = PARTITION) -> Model:
    """Assemble every body of ``scene`` into one set of particle and spring arrays, whose force
    loop runs in partitions of ``spring_partition`` particles (spring_runs.py)."""
    built = [body.build() for body in scene.bodies]
    offsets = np.cumsum([0] + [len(b.masses) for b in built])
    positions = np.concatenate([b.positions for b in built])
    mass = np.concatenate([b.masses for b in built])
    pinned = np.concatenate([b.pinned for b in built])
    radius = np.concatenate([b.radii if b.radii is not None else np.zeros(len(b.masses))
                             for b in built])

    # one parameter group per distinct (ks, kd): bodies alike share them, so that their springs
    # can share runs (spring_runs.py) and a scene of many bodies keeps a small table
    group_of, springs, groups, kinds = {}, [], [], []
    for body, start in zip(built, offsets):
        for kind, params in body.spring_parameters.items():
            members = body.spring_kind == kind
            if not members.any():
                continue
            if body.spring_constants is None:
                constants = np.array([[params.ks, params.kd]])
                inverse = np.zeros(members.sum(), np.int64)
            else:
                constants, inverse = np.unique(body.spring_constants[members], axis=0,
                                               return_inverse=True)
            number = np.array([group_of.setdefault((float(ks), float(kd)), len(group_of))
                               for ks, kd in constants], np.int32)
            springs.append(body.springs[members] + np.int32(start))
            groups.append(number[inverse.ravel()])
            kinds.append(body.spring_kind[members])
    group_ks = [ks for ks, kd in group_of]
    group_kd = [kd for ks, kd in group_of]
    springs = np.concatenate(springs) if springs else np.empty((0, 2), np.int32)
    groups = np.concatenate(groups) if groups else np.empty(0, np.int32)
    kinds = np.concatenate(kinds) if kinds else np.empty(0, np.int8)
    # Sorting by the first particle makes the force loop's writes walk memory in order.
    order = np.argsort(springs[:, 0], kind="stable")
    springs, groups, kinds = springs[order], groups[order], kinds[order]
    rest_length = np.linalg.norm(positions[springs[:, 0]] - positions[springs[:, 1]], axis=1)

    attached = pack_attachments(getattr(scene, "attachments", ()), built, offsets)
    terrain_offset = np.concatenate([b.terrain_offsets if b.terrain_offsets is not None
                                     else radius[start:start + len(b.masses)]
                                     for b, start in zip(built, offsets)])
    arrays = ModelArrays(
        inv_mass=np.where(pinned, 0.0, 1.0 / mass), radius=radius,
        terrain_offset=terrain_offset,
        gravity=np.asarray(scene.gravity, float), drag=particle_drag(scene, built),
        springs=np.ascontiguousarray(springs, dtype=np.uint32), rest_length=rest_length,
        spring_group=groups,
        group_ks=np.asarray(group_ks, float), group_kd=np.asarray(group_kd, float),
        **build_spring_runs(springs, groups, rest_length),
        spring_partition=checked_partition(spring_partition),
        **pack_terrains(scene.terrains, float(terrain_offset.max(initial=0.0))),
        **pack_world(scene.terrains, built, offsets),
        clock=np.zeros(CLOCK_SLOTS), **pack_wind(scene.wind),
        **wind_surface(scene, built, offsets),
        **collision_arrays(scene.bodies, built, radius),
        **sheet_arrays(built, offsets),
        **surface_contact_arrays(scene.bodies, built, offsets, attached["attachment_nodes"]),
        **attached, term_tables=tuple(term.pack(scene, built, offsets) for term in TERMS))
    # Numba compiles a kernel once per layout of its arguments: one Fortran-ordered table (a
    # cloth's triangles) compiled every kernel a second time.
    arrays = ModelArrays(*(np.ascontiguousarray(a) if isinstance(a, np.ndarray) else a
                           for a in arrays))
    bodies = tuple(body_slice(spec, b, i, int(offsets[i]), int(offsets[i + 1]))
                   for i, (spec, b) in enumerate(zip(scene.bodies, built)))
    velocities = np.concatenate([b.velocities for b in built])
    velocities[pinned] = 0.0
    # hard attachments hold from the start (the springs' rest lengths are where the bodies
    # were built): the run starts from a state they allow
    hold_attachments(arrays, positions, velocities)
    return Model(arrays=arrays, mass=mass, pinned=pinned, spring_kind=kinds, bodies=bodies,
                 initial_positions=positions, initial_velocities=velocities,
                 terrains=tuple(scene.terrains), scene_bodies=tuple(scene.bodies))


def body_slice(spec, built, number: int, start: int, stop: int) -> BodySlice:
    """Where body ``number`` lies in the model, its surface in global particle numbers (or, for
    an embedded surface, its embedding's particles in global numbers)."""
    name = getattr(spec, "name", "") or f"{type(spec).__name__.lower()}{number}"
    if built.embedding is None:
        return BodySlice(name, start, stop, built.surface + start)
    embedding = Embedding(built.embedding.particles + start, built.embedding.weights)
    return BodySlice(name, start, stop, built.surface, embedding)


def particle_drag(scene, built) -> np.ndarray:
    """(P,) drag coefficient (N s/m): the scene's drag plus the body's own (cloth and balls carry
    the reference's 3.4e-4; a body without a ``drag`` setting adds nothing)."""
    return np.concatenate([np.full(len(b.masses), scene.drag + getattr(spec, "drag", 0.0), float)
                           for spec, b in zip(scene.bodies, built)])


def sheet_arrays(built, offsets) -> dict:
    """The sheets' triangles in global particle numbers, and each particle's triangles (CSR): a
    sheet is a body that is all surface (BuiltBody.sheet: a cloth)."""
    triangles = [sheet_surface(b).astype(np.int64) + start for b, start in zip(built, offsets)
                 if b.sheet]
    triangles = np.concatenate(triangles) if triangles else np.empty((0, 3), np.int64)
    corners = triangles.ravel()
    order = np.argsort(corners, kind="stable")
    counts = np.bincount(corners, minlength=int(offsets[-1]))
    return {"sheet_triangles": triangles,
            "triangle_start": np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
            "particle_triangles": (order // 3).astype(np.int64)}


def wind_surface(scene, built, offsets) -> dict:
    """The triangles of particles the wind blows on (none without wind): each body's surface,
    or its contact surface where the drawn one is embedded (a mesh body's lattice boundary);
    with their weights (wind.quads_both_ways)."""
    triangles = [np.empty((0, 3), np.int64)]
    if scene.wind is not None:
        for b, start in zip(built, offsets):
            own = sheet_surface(b) if b.embedding is None else b.collision_surface
            if own is not None and len(own):
                triangles.append(np.asarray(own, np.int64) + start)
    triangles, weights = quads_both_ways(np.concatenate(triangles))
    return {"wind_triangles": triangles, "wind_weights": weights}


def sheet_surface(built) -> np.ndarray:
    """A sheet's triangles of particles (its contact surface where its drawn one is a file's)."""
    return built.collision_surface if built.collision_surface is not None else built.surface


def collision_arrays(specs, built, radius) -> dict:
    """The ball tables of ModelArrays: which particles are balls and how each one collides."""
    is_ball = radius > 0
    ball_slot = np.full(len(radius), -1, np.int64)
    ball_slot[is_ball] = np.arange(np.count_nonzero(is_ball))
    settings = {name: [] for name in collision_parameters(None)}
    for spec, b in zip(specs, built):
        count = np.count_nonzero(b.radii > 0) if b.radii is not None else 0
        for name, value in collision_parameters(spec).items():
            settings[name].append(np.full(count, value))
    return {"balls": np.flatnonzero(is_ball).astype(np.int64), "ball_slot": ball_slot,
            **{name: np.concatenate(values) for name, values in settings.items()}}
