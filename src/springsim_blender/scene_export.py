"""The Blender scene as a springsim scene folder: ``scene.toml``, an OBJ per simulated object and
collider (world coordinates at the first frame), and what moves them.

Blender is Z up, springsim Y up: a Blender point (x, y, z) is springsim's (x, z, -y), the turn
Blender's OBJ importer undoes with its default axes, so the folder's meshes open in Blender where
they were. Every frame of the range is evaluated once (what Blender shows: keyframes, parents,
constraints, armatures, modifiers, shape keys) and each object's motion written as:

- an object that moves rigidly: ``motion`` keyframes at every frame (position and rotation vector
  about its origin), which springsim interpolates linearly between frames;
- a deforming one: a PC2 point cache of its evaluated vertices (springsim's ``animation`` table of
  a mesh terrain, or of a cloth's pin), in the mesh file's vertex order and coordinates.

Nothing here imports springsim: the folder is handed to it as a file.
"""
import math
import re
from dataclasses import dataclass
from pathlib import Path

import bpy
import numpy as np

from . import point_cache
from .toml_text import scene_text

B2S = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])   # Blender -> springsim
MODIFIER = "springsim"        # the Mesh Cache modifier the take plays through
HARD_PIN = 0.999              # a pin weight at least this is a hard pin
SOFT_LEVELS = 10              # soft pin weights are rounded to tenths: at most 9 soft pins
STILL = 1e-9                  # m: a vertex that moves less than this between frames is still


class SetupError(Exception):
    """A Blender setting springsim cannot simulate, said in one line."""


@dataclass
class Target:
    """A simulated object and where its vertices are among the take's points."""
    name: str
    file_name: str            # the object's name made safe for a file
    offset: int
    count: int
    to_local: np.ndarray      # (F, 4, 4): Blender world -> the object's own space, per frame


@dataclass
class Exported:
    folder: Path
    scene_file: Path
    fps: float
    frame_start: int
    frame_end: int
    targets: list

    @property
    def frame_count(self) -> int:
        return self.frame_end - self.frame_start + 1

    @property
    def point_count(self) -> int:
        return sum(target.count for target in self.targets)


@dataclass
class Sampled:
    """An object at every frame of the range: world matrices, and its evaluated vertices (in
    its own space) at the first frame, or at every frame when they change."""
    matrices: np.ndarray      # (F, 4, 4)
    vertices: np.ndarray      # (F, V, 3) or (1, V, 3)
    faces: list               # rows of vertex numbers, at the first frame

    @property
    def deforms(self) -> bool:
        return len(self.vertices) > 1

    @property
    def moves(self) -> bool:
        return bool(np.abs(self.matrices - self.matrices[0]).max() > STILL)

    def world(self, frame: int = 0) -> np.ndarray:
        """Vertices in springsim's world coordinates at ``frame`` (index into the range)."""
        local = self.vertices[frame if self.deforms else 0]
        matrix = self.matrices[frame]
        return (local @ matrix[:3, :3].T + matrix[:3, 3]) @ B2S.T


def setting(value) -> float:
    """A Blender float setting (stored as float32) as the decimal the artist typed: 0.01, not
    0.009999999776482582."""
    return float(str(np.float32(value)))


def frame_range(scene) -> tuple[int, int]:
    settings = scene.springsim
    if settings.use_frame_range:
        return settings.frame_start, settings.frame_end
    return scene.frame_start, scene.frame_end


def scene_fps(scene) -> float:
    return scene.render.fps / scene.render.fps_base


def simulated_objects(scene) -> list:
    return [obj for obj in scene.objects
            if obj.type == "MESH" and obj.springsim.role in ("CLOTH", "BODY", "COLLIDER")]


def export_scene(scene, folder) -> Exported:
    """Write the scene folder for ``scene``'s frame range into ``folder``; the simulated objects'
    places among the take's points. A setting springsim cannot take raises SetupError."""
    folder = Path(folder)
    start, end = frame_range(scene)
    if end <= start:
        raise SetupError(f"frame range {start}-{end}: the last frame must come after the first")
    objects = simulated_objects(scene)
    moving = [obj for obj in objects if obj.springsim.role != "COLLIDER"]
    if not moving:
        raise SetupError("no object has the springsim role Cloth or Jelly body (Physics tab)")
    fps = scene_fps(scene)
    sampled = sample(scene, objects, range(start, end + 1))
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    times = [(frame - start) / fps for frame in range(start, end + 1)]
    names = file_names(objects)
    settings = scene.springsim
    description = {
        "name": scene.name, "integrator": settings.integrator,
        "dt": 1.0 / (fps * settings.substeps), "duration": (end - start) / fps,
        "gravity": [setting(g) + 0.0 for g in B2S @ np.asarray(settings.gravity, float)],
        "bodies": [], "terrains": []}
    targets, offset = [], 0
    for obj in moving:
        data = sampled[obj.name]
        mesh_file = write_mesh(folder, names[obj.name], data)
        if obj.springsim.role == "CLOTH":
            body = cloth_table(obj, mesh_file, data, times, fps, folder, names[obj.name])
        else:
            body = body_table(obj, mesh_file)
        body["self_collision"] = bool(settings.self_collision)
        description["bodies"].append(body)
        count = data.vertices.shape[1]
        to_local = np.linalg.inv(data.matrices)
        targets.append(Target(obj.name, names[obj.name], offset, count, to_local))
        offset += count
    for obj in objects:
        if obj.springsim.role == "COLLIDER":
            data = sampled[obj.name]
            mesh_file = write_mesh(folder, names[obj.name], data)
            description["terrains"].append(
                collider_table(obj, mesh_file, data, times, fps, folder, names[obj.name]))
    wind = wind_table(scene, settings)
    if wind is not None:
        description["wind"] = wind
    scene_file = folder / "scene.toml"
    scene_file.write_text(scene_text(description, comment=(
        f"springsim scene exported from Blender: frames {start}-{end} at {fps:g} fps\n"
        f"run it: springsim run scene.toml --fps {fps!r} --export take.pc2")))
    return Exported(folder, scene_file, fps, start, end, targets)


def sample(scene, objects, frames) -> dict:
    """Every object at every frame, with the take's own Mesh Cache modifiers switched off."""
    ours = [(m, m.show_viewport) for obj in objects for m in obj.modifiers if m.name == MODIFIER]
    for modifier, _ in ours:
        modifier.show_viewport = False
    current = scene.frame_current
    matrices = {obj.name: [] for obj in objects}
    vertices = {obj.name: [] for obj in objects}
    faces = {}
    try:
        for frame in frames:
            scene.frame_set(frame)
            depsgraph = bpy.context.evaluated_depsgraph_get()
            for obj in objects:
                evaluated = obj.evaluated_get(depsgraph)
                matrices[obj.name].append(np.array(evaluated.matrix_world, float))
                if frame == frames[0] or may_deform(obj):
                    mesh = evaluated.to_mesh()
                    vertices[obj.name].append(mesh_vertices(mesh))
                    if frame == frames[0]:
                        faces[obj.name] = mesh_faces(mesh)
                    evaluated.to_mesh_clear()
    finally:
        scene.frame_set(current)
        for modifier, shown in ours:
            modifier.show_viewport = shown
    result = {}
    for obj in objects:
        counts = {len(frame) for frame in vertices[obj.name]}
        if len(counts) > 1:
            raise SetupError(f"{obj.name!r} changes its vertex count from frame to frame "
                             f"({min(counts)} to {max(counts)}): a point cache needs one count")
        points = np.stack(vertices[obj.name])
        if len(points) > 1 and np.abs(points - points[0]).max() <= STILL:
            points = points[:1]
        result[obj.name] = Sampled(np.stack(matrices[obj.name]), points, faces[obj.name])
    return result


def may_deform(obj) -> bool:
    """Modifiers (armatures, ...) and shape keys may change a mesh from frame to frame."""
    shape_keys = obj.data.shape_keys is not None
    return shape_keys or any(m.show_viewport for m in obj.modifiers if m.name != MODIFIER)


def mesh_vertices(mesh) -> np.ndarray:
    co = np.empty(len(mesh.vertices) * 3)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def mesh_faces(mesh) -> list:
    corners = np.empty(len(mesh.loops), np.int64)
    mesh.loops.foreach_get("vertex_index", corners)
    starts = np.empty(len(mesh.polygons), np.int64)
    totals = np.empty(len(mesh.polygons), np.int64)
    mesh.polygons.foreach_get("loop_start", starts)
    mesh.polygons.foreach_get("loop_total", totals)
    return [corners[s:s + t].tolist() for s, t in zip(starts, totals)]


def file_names(objects) -> dict:
    """A file name per object: its name with characters unsafe in files replaced, made unique."""
    names, used = {}, set()
    for obj in objects:
        base = re.sub(r"[^\w.-]+", "_", obj.name).strip("._") or "object"
        name, count = base, 1
        while name.lower() in used:
            count += 1
            name = f"{base}_{count}"
        used.add(name.lower())
        names[obj.name] = name
    return names


def write_mesh(folder: Path, name: str, data: Sampled) -> str:
    """The object's mesh at the first frame, in springsim's world coordinates, as an OBJ."""
    if not data.faces:
        raise SetupError(f"object {name!r} has no faces: springsim needs a surface")
    vertices = data.world(0)
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in vertices.tolist()]
    lines += ["f " + " ".join(str(v + 1) for v in face) for face in data.faces]
    relative = f"meshes/{name}.obj"
    (folder / relative).write_text("\n".join(lines) + "\n")
    return relative


def motion_table(data: Sampled, times: list) -> dict:
    """The object's rigid motion since the first frame as springsim keyframes about its origin:
    x(t) = pivot + position(t) + R(t) (x - pivot)."""
    first = np.linalg.inv(data.matrices[0])
    pivot = B2S @ data.matrices[0][:3, 3]
    keys, previous = [], np.zeros(3)
    for time, matrix in zip(times, data.matrices):
        relative = matrix @ first
        rotation = B2S @ orthonormal(relative[:3, :3]) @ B2S.T
        shift = B2S @ relative[:3, 3]
        position = shift + rotation @ pivot - pivot
        vector = rotation_vector(rotation, previous)
        previous = vector
        angle = float(np.linalg.norm(vector))
        axis = vector / angle if angle > 0 else np.array([0.0, 1.0, 0.0])
        keys.append({"time": float(time), "position": [float(p) for p in position],
                     "rotation_degrees": math.degrees(angle),
                     "rotation_axis": [float(a) for a in axis]})
    return {"keyframes": keys, "interpolation": "linear",
            "pivot": [float(p) for p in pivot]}


def orthonormal(matrix: np.ndarray) -> np.ndarray:
    """The rotation nearest ``matrix`` (a scale changing over time is not a rigid motion)."""
    u, _, vt = np.linalg.svd(matrix)
    rotation = u @ vt
    if np.linalg.det(rotation) < 0:
        u[:, -1] *= -1
        rotation = u @ vt
    return rotation


def rotation_vector(rotation: np.ndarray, previous: np.ndarray) -> np.ndarray:
    """Axis times angle of ``rotation``, the one of its equivalents (angle + 2 pi k) nearest
    ``previous``, so that linear interpolation between frames turns the short way round and a
    spin keeps counting past half a turn."""
    cos = np.clip((np.trace(rotation) - 1) / 2, -1.0, 1.0)
    angle = math.acos(cos)
    if angle < 1e-12:
        axis = previous / np.linalg.norm(previous) if np.any(previous) else np.zeros(3)
    elif math.pi - angle < 1e-6:
        axis = np.sqrt(np.maximum((np.diag(rotation) + 1) / 2, 0))
        largest = int(np.argmax(axis))
        axis = (rotation[:, largest] + np.eye(3)[largest]) / 2
        axis /= np.linalg.norm(axis)
    else:
        axis = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                         rotation[1, 0] - rotation[0, 1]]) / (2 * math.sin(angle))
    if not np.any(axis):
        return np.zeros(3)
    best = None
    for turns in range(-3, 4):
        candidate = axis * (angle + 2 * math.pi * turns)
        if best is None or np.linalg.norm(candidate - previous) < np.linalg.norm(best - previous):
            best = candidate
    return best


def animation_table(data: Sampled, folder: Path, name: str, fps: float) -> dict:
    """A PC2 of the object's evaluated vertices at every frame, in springsim's world
    coordinates and the mesh file's vertex order, for an ``animation`` table."""
    relative = f"meshes/{name}.pc2"
    points = np.stack([data.world(frame) for frame in range(len(data.matrices))])
    point_cache.write(folder / relative, points, start_frame=0.0)
    return {"file": relative, "fps": float(fps), "start": 0.0}


def path_table(data: Sampled, times, fps, folder, name) -> dict:
    """What moves a collider or a pin: nothing, rigid keyframes, or a point cache."""
    if data.deforms:
        return {"animation": animation_table(data, folder, name, fps)}
    if data.moves:
        return {"motion": motion_table(data, times)}
    return {}


def cloth_table(obj, mesh_file, data, times, fps, folder, name) -> dict:
    settings = obj.springsim
    body = {"type": "cloth", "file": mesh_file, "pinned": "none",
            "thickness": setting(settings.thickness), "friction": setting(settings.friction),
            "material": {key: setting(getattr(settings, key)) for key in (
                "density", "stretch", "shear", "bend", "stretch_damping", "shear_damping",
                "bend_damping")}}
    pins = pin_tables(obj, data, times, fps, folder, name)
    if pins:
        body["pins"] = pins
    return body


def pin_tables(obj, data: Sampled, times, fps, folder, name) -> list:
    """The pin vertex group as pins: weight 1 a hard pin, lower weights soft pins of that share
    of the pin stiffness (rounded to tenths, a pin per tenth used), all following the object as
    Blender animates it."""
    settings = obj.springsim
    if not settings.pin_group:
        return []
    group = obj.vertex_groups.get(settings.pin_group)
    if group is None:
        raise SetupError(f"{obj.name}: pin group {settings.pin_group!r} is not a vertex group "
                         f"of the object (it has: {', '.join(g.name for g in obj.vertex_groups)})")
    if len(obj.data.vertices) != data.vertices.shape[1]:
        raise SetupError(f"{obj.name}: its modifiers change the vertex count, so the pin group's "
                         "vertices are not the simulated ones; apply them or pin without them")
    numbers = particle_numbers(data.world(0))
    levels = {}
    for vertex in obj.data.vertices:
        for element in vertex.groups:
            if element.group == group.index and element.weight > 0:
                weight = element.weight
                level = SOFT_LEVELS if weight >= HARD_PIN else round(weight * SOFT_LEVELS)
                levels.setdefault(max(level, 1), set()).add(numbers[vertex.index])
    if not levels:
        raise SetupError(f"{obj.name}: pin group {group.name!r} has no vertex of weight > 0")
    path = path_table(data, times, fps, folder, f"{name}_pins")
    pins = []
    for level in sorted(levels, reverse=True):
        pin = {"particles": sorted(levels[level])}
        if level < SOFT_LEVELS:
            pin["stiffness"] = float(settings.pin_stiffness * level / SOFT_LEVELS)
            pin["damping"] = setting(settings.pin_damping)
        pins.append({**pin, **path})
    return pins


def particle_numbers(vertices: np.ndarray) -> list:
    """springsim's particle number of each vertex: vertices at the same place are welded into
    one particle, numbered by first appearance in the file."""
    welded, numbers = {}, []
    for row in vertices.tolist():
        numbers.append(welded.setdefault(tuple(row), len(welded)))
    return numbers


def body_table(obj, mesh_file) -> dict:
    settings = obj.springsim
    springs = {"ks": setting(settings.spring_ks), "kd": setting(settings.spring_kd)}
    return {"type": "mesh", "file": mesh_file, "particles": int(settings.particles),
            "spacing": "auto", "particle_mass": setting(settings.particle_mass),
            "thickness": setting(settings.thickness), "friction": setting(settings.friction),
            "structural": dict(springs), "shear": dict(springs), "bend": dict(springs)}


def collider_table(obj, mesh_file, data, times, fps, folder, name) -> dict:
    settings = obj.springsim
    shared = overshared_edges(data.faces)
    if shared:
        raise SetupError(
            f"collider {obj.name!r} is not manifold: {shared} edge(s) are shared by more than "
            "two faces, so it has no inside and outside to keep bodies out of (Edit Mode: "
            "Select > Select All by Trait > Non Manifold)")
    terrain = {"type": "mesh", "file": mesh_file, "friction": setting(settings.friction),
               "restitution": setting(settings.restitution),
               "resolution": int(settings.resolution)}
    terrain.update(path_table(data, times, fps, folder, name))
    return terrain


def overshared_edges(faces) -> int:
    """How many edges more than two faces share (an open mesh's boundary is allowed: springsim
    collides with it on the side its normals face)."""
    counts = {}
    for face in faces:
        for a, b in zip(face, face[1:] + face[:1]):
            edge = (a, b) if a < b else (b, a)
            counts[edge] = counts.get(edge, 0) + 1
    return sum(1 for count in counts.values() if count > 2)


def wind_table(scene, settings) -> dict | None:
    """Blender's Wind force fields as springsim's air velocity (strength in m/s along each
    field's local Z axis, summed); Turbulence fields as its gusts. None: still air, no force."""
    velocity, gusts = np.zeros(3), None
    for obj in scene.objects:
        field = getattr(obj, "field", None)
        if field is None or obj.hide_render:
            continue
        if field.type == "WIND":
            direction = np.array(obj.matrix_world, float)[:3, 2]
            velocity += field.strength * direction / np.linalg.norm(direction)
        elif field.type == "TURBULENCE" and gusts is None:
            gusts = {"strength": abs(setting(field.strength)), "length": gust_length(field),
                     "seed": int(field.seed) if hasattr(field, "seed") else 0}
    if not settings.use_air and not np.any(velocity) and gusts is None:
        return None
    wind = {"velocity": [float(v) for v in B2S @ velocity],
            "density": setting(settings.air_density), "drag": setting(settings.air_drag)}
    if gusts is not None:
        speed = float(np.linalg.norm(velocity))
        if speed > 0:
            gusts["strength"] /= speed           # a share of the mean wind speed
        wind["gusts"] = gusts
    return wind


def gust_length(field) -> float:
    """A Turbulence field's Size as the gusts' length (m). Blender scales its noise by 1/Size
    only when Size is not 0 (its default): Size 0 is the unscaled noise, whose features are about
    1 m, not gusts of no size."""
    size = setting(field.size)
    return size if size > 0 else 1.0
