"""What the viewer and the headless renderer draw, registered once per model with polyscope.

Particles as small spheres, springs as thin curve networks (one per kind, in the course colours),
body surfaces with smooth normals (open ones such as cloth in a second colour underneath), balls
as spheres of their contact radius, the terrains, the pinned particles as larger dark dots, the
mean wind's direction as an arrow above the bodies, and (off by default) the body-body surface
contacts of the state as points with short normals (contacts.py finds them). ``update(positions)``
moves everything to a new state; ``DrawOptions`` says what is shown.
"""
from dataclasses import dataclass, fields

import numpy as np
import polyscope as ps

from ..bodies.pins import pinned_particles as numbered_pins
from ..errors import require
from ..meshfiles import is_closed
from ..springs import SpringKind
from ..surfaces import body_surface
from ..wind import ON as WIND_ON
from . import colors
from .contacts import contact_marks, has_body_contact


@dataclass
class DrawOptions:
    """Which parts are shown; spring kinds go by their names (structural, shear, bend, face)."""

    surfaces: bool = True
    particles: bool = False
    structural: bool = False
    shear: bool = False
    bend: bool = False
    face: bool = False
    balls: bool = True
    terrains: bool = True
    pins: bool = True
    wind: bool = True
    contacts: bool = False

    @classmethod
    def only(cls, names) -> "DrawOptions":
        """Options that show just ``names`` (for example ``["surfaces", "structural"]``)."""
        allowed = [f.name for f in fields(cls)]
        for name in names:
            require(name in allowed, "draw", name, "must be among " + ", ".join(allowed))
        return cls(**{name: name in names for name in allowed})


class _Part:
    """One polyscope structure, the toggle that shows it, and how it follows the particles."""

    def __init__(self, structure, toggle: str, follow=None):
        self.structure, self.toggle, self.follow = structure, toggle, follow
        self.stale = False


class SceneDrawing:
    """Every structure of one model. Creating one removes whatever polyscope showed before."""

    def __init__(self, model, options: DrawOptions | None = None, positions=None):
        ps.remove_all_structures()
        self.model = model
        self.options = options or DrawOptions()
        self.positions = np.array(model.initial_positions if positions is None else positions)
        self.spacing = typical_spacing(model)
        self.parts: list[_Part] = []
        self._add_surfaces()
        self._add_springs()
        self._add_particles_and_balls()
        self._add_terrains()
        self._add_pins()
        self._add_wind()
        self._add_contacts()
        self.apply_options()

    # --- building -------------------------------------------------------------------------
    def _add_surfaces(self) -> None:
        for number, body in enumerate(self.model.bodies):
            surface = body_surface(body, self.positions)
            if surface.triangles.size == 0:
                continue
            # only the vertices the triangles use (a cube's surface skips its inner particles)
            used, triangles = np.unique(surface.triangles, return_inverse=True)
            triangles = triangles.reshape(-1, 3)
            color = colors.BODY_COLORS[number % len(colors.BODY_COLORS)]
            mesh = ps.register_surface_mesh(f"surface {number}: {body.name}",
                                            surface.vertices[used], triangles,
                                            smooth_shade=True, color=color, edge_width=0.0)
            if is_closed(triangles):
                mesh.set_back_face_policy("identical")
            else:  # cloth: both sides visible, the underside in its own colour
                mesh.set_back_face_policy("custom")
                mesh.set_back_face_color(colors.CLOTH_BACK_COLOR)
            self.parts.append(_Part(mesh, "surfaces", lambda x, m=mesh, b=body, v=used:
                                    m.update_vertex_positions(body_surface(b, x).vertices[v])))

    def _add_springs(self) -> None:
        springs = self.model.springs.astype(np.int64)
        for kind in SpringKind:
            members = self.model.spring_kind == kind
            if not members.any():
                continue
            nodes, edges = np.unique(springs[members], return_inverse=True)
            network = ps.register_curve_network(f"springs: {kind.label}", self.positions[nodes],
                                                edges.reshape(-1, 2),
                                                color=colors.SPRING_COLORS[kind])
            network.set_radius(0.03 * self.spacing, relative=False)
            self.parts.append(_Part(network, kind.label,
                                    lambda x, c=network, n=nodes: c.update_node_positions(x[n])))

    def _add_particles_and_balls(self) -> None:
        radius = self.model.arrays.radius
        points = np.flatnonzero(radius == 0.0)
        if points.size:
            cloud = ps.register_point_cloud("particles", self.positions[points],
                                            color=colors.PARTICLE_COLOR)
            cloud.set_radius(0.12 * self.spacing, relative=False)
            self.parts.append(_Part(cloud, "particles",
                                    lambda x, c=cloud, i=points: c.update_point_positions(x[i])))
        balls = np.flatnonzero(radius > 0.0)
        if balls.size:
            cloud = ps.register_point_cloud("balls", self.positions[balls], color=colors.BALL_COLOR)
            cloud.add_scalar_quantity("radius", radius[balls])
            cloud.set_point_radius_quantity("radius", autoscale=False)
            self.parts.append(_Part(cloud, "balls",
                                    lambda x, c=cloud, i=balls: c.update_point_positions(x[i])))

    def _add_terrains(self) -> None:
        self.moving_terrains = []
        for number, terrain in enumerate(self.model.terrains):
            name = f"terrain {number}: {type(terrain).__name__.lower()}"
            drawn = _TerrainDrawing(name, terrain, self.positions)
            if terrain.moves():
                self.moving_terrains.append(drawn)
            follow = drawn.follow if drawn.shape.recentre_distance is not None else None
            self.parts.append(_Part(drawn.mesh, "terrains", follow))
            drawn.part = self.parts[-1]

    def _add_pins(self) -> None:
        held = np.flatnonzero(pinned_particles(self.model))
        if held.size == 0:
            return
        cloud = ps.register_point_cloud("pins", self.positions[held], color=colors.PIN_COLOR)
        cloud.set_radius(0.25 * self.spacing, relative=False)
        self.parts.append(_Part(cloud, "pins",
                                lambda x, c=cloud, i=held: c.update_point_positions(x[i])))

    def _add_wind(self) -> None:
        self.wind = _WindDrawing(self.model, self.positions) if has_wind(self.model) else None
        if self.wind is not None:
            self.parts.append(_Part(self.wind.cloud, "wind"))

    def _add_contacts(self) -> None:
        if not has_body_contact(self.model):
            return
        drawn = _ContactDrawing(self.model.arrays, 0.15 * self.spacing)
        self.parts.append(_Part(drawn, "contacts", drawn.follow))
        self.parts[-1].stale = True     # found only once shown: hidden, they cost nothing

    # --- use ------------------------------------------------------------------------------
    def update(self, positions, time: float | None = None) -> bool:
        """Move everything shown to ``positions``, and the terrains that move to where they are
        at ``time`` (s); a non-finite state is not drawn (False)."""
        positions = np.asarray(positions, float)
        if not np.all(np.isfinite(positions)):
            return False
        self.positions = positions.copy()
        if time is not None:
            for drawn in self.moving_terrains:
                drawn.at_time(time)
            if self.wind is not None:
                self.wind.at_time(time)
        for part in self.parts:
            if part.follow is None:
                continue
            if getattr(self.options, part.toggle):
                part.follow(self.positions)
                part.stale = False
            else:
                part.stale = True       # updated when shown again
        return True

    def apply_options(self, options: DrawOptions | None = None) -> None:
        """Show and hide parts after a change of ``options``."""
        if options is not None:
            self.options = options
        for part in self.parts:
            shown = getattr(self.options, part.toggle)
            if shown and part.stale and part.follow is not None:
                part.follow(self.positions)
                part.stale = False
            part.structure.set_enabled(shown)

    def structure_names(self, toggle: str) -> list[str]:
        return [part.structure.get_name() for part in self.parts if part.toggle == toggle]


class _TerrainDrawing:
    """A terrain's display mesh (its kind's ``display_mesh``), rebuilt around the bodies when
    the mesh follows them (a plane's patch) and they leave its middle."""

    def __init__(self, name, terrain, positions):
        self.name, self.terrain = name, terrain
        self.extent = float(np.max(positions.max(axis=0) - positions.min(axis=0)))
        self.part, self.time = None, None
        self._build(positions.mean(axis=0))

    def _build(self, near) -> None:
        shape = self.terrain.display_mesh(near, self.extent)
        color = colors.BOWL_COLOR if shape.color == "bowl" else colors.TERRAIN_COLOR
        self.shape = shape
        self.mesh = ps.register_surface_mesh(self.name, shape.vertices, shape.triangles,
                                             color=color, smooth_shade=shape.smooth)
        if shape.checker is not None:
            face_colors = np.asarray(colors.TERRAIN_CHECKER_COLORS)[shape.checker]
            self.mesh.add_color_quantity("checker", face_colors, defined_on="faces",
                                         enabled=True)
        if shape.cull_back:
            self.mesh.set_back_face_policy("cull")
        elif shape.two_sided:
            self.mesh.set_back_face_policy("identical")
        if self.part is not None:
            self.part.structure = self.mesh

    def follow(self, positions) -> None:
        near = positions.mean(axis=0)
        if self.shape.needs_recentring(near):
            self._build(near)
            if self.time is not None:
                self.at_time(self.time)

    def at_time(self, t: float) -> None:
        """Draw the terrain where its motion or animation has it at time t (s)."""
        self.time = t
        self.mesh.update_vertex_positions(self.terrain.vertices_at(self.shape.vertices, t))


class _ContactDrawing:
    """The contacts of the state: a point cloud of contact points and a curve network of their
    normals, registered anew whenever they are found (their number changes from state to state).
    Stands for both structures in a _Part (``set_enabled``, ``get_name``)."""

    POINTS, NORMALS = "contacts", "contact normals"

    def __init__(self, arrays, radius: float):
        self.arrays, self.radius = arrays, radius
        self.enabled = False
        self._register(np.empty((0, 3)), np.empty((0, 3)))

    def follow(self, positions) -> None:
        marks = contact_marks(self.arrays, positions)
        self._register(marks.points, marks.ends)

    def _register(self, points, ends) -> None:
        cloud = ps.register_point_cloud(self.POINTS, points, color=colors.CONTACT_COLOR,
                                        enabled=self.enabled)
        cloud.set_radius(self.radius, relative=False)
        count = len(points)
        segments = np.arange(2 * count).reshape(count, 2)
        nodes = np.stack([points, ends], axis=1).reshape(-1, 3)
        normals = ps.register_curve_network(self.NORMALS, nodes, segments,
                                            color=colors.CONTACT_NORMAL_COLOR,
                                            enabled=self.enabled)
        normals.set_radius(0.3 * self.radius, relative=False)

    def set_enabled(self, shown: bool) -> None:
        self.enabled = shown
        for name, get in ((self.POINTS, ps.get_point_cloud),
                          (self.NORMALS, ps.get_curve_network)):
            get(name).set_enabled(shown)

    def get_name(self) -> str:
        return self.POINTS


class _WindDrawing:
    """An arrow along the mean wind (WindArrow); ``base`` and ``arrow`` as now drawn."""

    def __init__(self, model, positions):
        self.shape = WindArrow.over(positions, model.arrays.wind_keys)
        self.cloud = ps.register_point_cloud("wind", self.shape.centre[None],
                                             color=colors.WIND_COLOR)
        self.cloud.set_radius(0.02 * self.shape.length, relative=False)
        self.at_time(0.0)

    def at_time(self, t: float) -> None:
        self.base, self.arrow = self.shape.at(t)
        self.cloud.update_point_positions(self.base[None])
        self.cloud.add_vector_quantity("air", self.arrow[None], enabled=True,
                                       vectortype="ambient", radius=0.05 * self.shape.length,
                                       color=colors.WIND_COLOR)


@dataclass
class WindArrow:
    """An arrow along the mean wind (its keyed velocity; the gusts left out), centred on the top
    of the bodies at the start (where the camera frames them), a third of their size long
    whatever the speed: it shows the way the air moves; the speed is in the scene. Drawn by the
    viewer, the replays and the browser replay alike."""

    centre: np.ndarray   # (3,) m
    length: float        # m
    keys: np.ndarray     # (K, 4) the wind's keys

    @classmethod
    def over(cls, positions, keys) -> "WindArrow":
        low, high = positions.min(axis=0), positions.max(axis=0)
        centre = np.array([(low[0] + high[0]) / 2, high[1], (low[2] + high[2]) / 2])
        return cls(centre, max(float(np.max(high - low)), 0.1) / 3, np.asarray(keys, float))

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(base, arrow) at time t: the arrow runs from base to base + arrow (none in still
        air)."""
        velocity = mean_wind(self.keys, t)
        speed = float(np.linalg.norm(velocity))
        arrow = velocity / speed * self.length if speed > 0 else np.zeros(3)
        return self.centre - arrow / 2, arrow


def mean_wind(keys: np.ndarray, t: float) -> np.ndarray:
    """The keyed wind velocity (m/s) at time t, as wind.air_at has it, before the gusts:
    linear between keys, held before the first and after the last."""
    return np.array([np.interp(t, keys[:, 0], keys[:, 1 + axis]) for axis in range(3)])


def pinned_particles(model) -> np.ndarray:
    """(P,) bool: every particle a pin holds or moves (bodies/pins.pinned_particles; a
    recording's model, replay.recorded_model, keeps them in its ``pinned``)."""
    mask = np.zeros(model.particle_count, bool)
    mask[numbered_pins(model)] = True
    return mask


def has_wind(model) -> bool:
    """Whether the model has a [wind] table (a recording's model keeps its keys)."""
    settings = getattr(model.arrays, "wind_settings", None)
    return settings is not None and bool(settings[WIND_ON])


def typical_spacing(model) -> float:
    """A length (m) that sets the drawn size of particles and springs: the median rest length
    of structural springs (of any springs if none), else a tenth of the bodies' size."""
    rest = model.arrays.rest_length
    structural = rest[model.spring_kind == SpringKind.STRUCTURAL]
    if structural.size:
        return float(np.median(structural))
    if rest.size:
        return float(np.median(rest))
    x = model.initial_positions
    return max(0.1 * float(np.max(x.max(axis=0) - x.min(axis=0))), 0.05)

