"""What the viewer and the headless renderer draw, registered once per model with polyscope.

Particles as small spheres, springs as thin curve networks (one per kind, in the course colours),
body surfaces with smooth normals (open ones such as cloth in a second colour underneath), balls
as spheres of their contact radius, and the terrains. ``update(positions)`` moves everything to
a new state; ``DrawOptions`` says what is shown.
"""
from dataclasses import dataclass, fields

import numpy as np
import polyscope as ps

from ..errors import require
from ..springs import SpringKind
from ..terrains import Bowl, Plane, Sphere
from . import colors
from .terrain_meshes import bowl_mesh, plane_patch, sphere_mesh


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
        self.apply_options()

    # --- building -------------------------------------------------------------------------
    def _add_surfaces(self) -> None:
        for number, body in enumerate(self.model.bodies):
            if body.surface.size == 0:
                continue
            vertices, triangles = np.unique(body.surface, return_inverse=True)
            triangles = triangles.reshape(-1, 3)
            color = colors.BODY_COLORS[number % len(colors.BODY_COLORS)]
            mesh = ps.register_surface_mesh(f"surface {number}: {body.name}",
                                            self.positions[vertices], triangles,
                                            smooth_shade=True, color=color, edge_width=0.0)
            if is_closed(triangles):
                mesh.set_back_face_policy("identical")
            else:  # cloth: both sides visible, the underside in its own colour
                mesh.set_back_face_policy("custom")
                mesh.set_back_face_color(colors.CLOTH_BACK_COLOR)
            self.parts.append(_Part(mesh, "surfaces",
                                    lambda x, m=mesh, v=vertices: m.update_vertex_positions(x[v])))

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
        for number, terrain in enumerate(self.model.terrains):
            name = f"terrain {number}: {type(terrain).__name__.lower()}"
            if isinstance(terrain, Plane):
                patch = _PlanePatch(name, terrain, self.positions)
                self.parts.append(_Part(patch.mesh, "terrains", patch.follow))
                patch.part = self.parts[-1]
            elif isinstance(terrain, Bowl):
                vertices, triangles = bowl_mesh(terrain.center, terrain.radius)
                mesh = ps.register_surface_mesh(name, vertices, triangles, smooth_shade=True,
                                                color=colors.BOWL_COLOR)
                mesh.set_back_face_policy("cull")
                self.parts.append(_Part(mesh, "terrains"))
            elif isinstance(terrain, Sphere):
                vertices, triangles = sphere_mesh(terrain.center, terrain.radius)
                mesh = ps.register_surface_mesh(name, vertices, triangles, smooth_shade=True,
                                                color=colors.TERRAIN_COLOR)
                self.parts.append(_Part(mesh, "terrains"))

    # --- use ------------------------------------------------------------------------------
    def update(self, positions) -> bool:
        """Move everything shown to ``positions``; a non-finite state is not drawn (False)."""
        positions = np.asarray(positions, float)
        if not np.all(np.isfinite(positions)):
            return False
        self.positions = positions.copy()
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


class _PlanePatch:
    """A checkered square of a plane under the bodies, moved along when they leave its middle."""

    def __init__(self, name, plane, positions):
        self.name, self.plane = name, plane
        low = positions.min(axis=0)
        high = positions.max(axis=0)
        extent = float(np.max(high - low))
        self.cell = float(10.0 ** np.round(np.log10(max(extent, 1e-3) / 4)))
        self.half_size = max(40.0 * self.cell, 10.0 * extent)
        self.part = None
        self._build(positions.mean(axis=0))

    def _build(self, near) -> None:
        vertices, triangles, checker = plane_patch(self.plane.point, self.plane.unit_normal(),
                                                   near, self.half_size, self.cell)
        self.center = vertices.mean(axis=0)
        self.mesh = ps.register_surface_mesh(self.name, vertices, triangles,
                                             color=colors.TERRAIN_COLOR)
        cell_colors = np.asarray(colors.TERRAIN_CHECKER_COLORS)[checker]
        self.mesh.add_color_quantity("checker", cell_colors, defined_on="faces", enabled=True)
        if self.part is not None:
            self.part.structure = self.mesh

    def follow(self, positions) -> None:
        near = positions.mean(axis=0)
        offset = near - self.center
        offset -= (offset @ self.plane.unit_normal()) * self.plane.unit_normal()
        if np.linalg.norm(offset) > self.half_size / 3:
            self._build(near)


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


def is_closed(triangles: np.ndarray) -> bool:
    """Whether every edge of the triangle mesh is shared by exactly two triangles."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                                    triangles[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))
