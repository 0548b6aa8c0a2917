"""MkDocs hook: the pages that must not drift from the code, generated at every build.

- ``guide/scene-reference.md``: every key a scene file accepts (``springsim.scenefile.scene_keys``,
  which finds them as the scene-file reader does), its kind, default and what the validation
  allows. The *allowed* column is not written by hand: each key is set, in a scene that is valid
  otherwise, to a few probe values (a value of the wrong kind, negative, zero, large, a zero
  vector), the scene is validated, and the one-line messages of the ``SceneError`` raised for that
  key are the text. A new check in a ``validate`` method shows up here by itself.
- ``guide/cli-reference.md``: every command and option, walked from ``springsim.cli.build_parser``.
- ``gallery.md``: a picture and an animation of every built-in scene, from the list of scenes;
  the files are made by scripts/make_gallery.py, and one missing fails the strict build.
- ``changelog.md``: CHANGELOG.md at the repository root, as it is.

Units and one-line meanings are the only hand-written part (``NOTES`` below); the docs tests fail
when a key has none or a note names a key that no longer exists.
"""
import argparse
import copy
import dataclasses
import functools
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

GENERATED = {
    "guide/scene-reference.md": lambda: scene_reference_markdown(),
    "guide/cli-reference.md": lambda: cli_reference_markdown(),
    "gallery.md": lambda: gallery_markdown(),
    # its links point into docs/ from the repository root; the page sits at the site's root
    "changelog.md": lambda: (ROOT / "CHANGELOG.md").read_text(encoding="utf-8").replace(
        "](docs/", "]("),
}


def on_files(files, config):
    from mkdocs.structure.files import File

    for uri, make in GENERATED.items():
        files.append(File.generated(config, uri, content=make()))
    return files


# --- units and meanings: the hand-written part -------------------------------------------------
# Looked up as "GROUP/TYPE/KEY", then "GROUP/*/KEY", then "*/*/KEY", then "*/*/*.LAST" (a spring
# sub-table's ks and kd); KEY is the key within its body or terrain table.

SPRING_KINDS = "structural, shear, bend and face springs"
NOTES = {
    "scene/*/name": ("", "names the output (`springsim run` writes `NAME.npz`); a file's name "
                         "without `.toml` when left out"),
    "scene/*/bodies": ("", "the `[[bodies]]` tables, each with a `type` (below)"),
    "scene/*/terrains": ("", "the `[[terrains]]` tables, each with a `type` (below); none is free "
                             "fall"),
    "scene/*/integrator": ("", "the time integrator ([Physics](physics.md#integrators))"),
    "scene/*/dt": ("s", "time step"),
    "scene/*/duration": ("s", "how long `springsim run` simulates"),
    "scene/*/gravity": ("m/s²", "acceleration of gravity"),
    "scene/*/drag": ("N s/m", "viscous drag on every particle, force `-drag v`"),
    "scene/*/wind": ("", "moving air: `velocity` or `keyframes`, `density`, `drag`, "
                         "`friction`, `gusts` ([Scene files](../scene-files.md#wind))"),
    "scene/*/implicit": ("", "settings of `implicit_euler`, checked whatever the integrator"),
    "scene/*/attachments": ("", "the `[[attachments]]` tables: particles of one body bound to "
                                "another body's surface, hard or soft "
                                "([Scene files](../scene-files.md#attachments))"),
    "scene/*/attachments.N.body": ("", "the number of the body (from 0) whose particles are "
                                       "bound"),
    "scene/*/attachments.N.to": ("", "the number of another body, whose surface triangles "
                                     "receive them"),
    "scene/*/attachments.N.particles": ("", "particle numbers of `body` to bind"),
    "scene/*/attachments.N.region": ("", "a box; the particles of `body` that start inside it "
                                         "are bound"),
    "scene/*/attachments.N.region.min": ("m", "the box's lowest corner"),
    "scene/*/attachments.N.region.max": ("m", "the box's highest corner"),
    "scene/*/attachments.N.distance": ("m", "the farthest a chosen particle may start from the "
                                            "surface of `to`"),
    "scene/*/attachments.N.stiffness": ("N/m", "a soft attachment: a spring of zero length to "
                                               "the triangle's point; left out, a hard one"),
    "scene/*/attachments.N.damping": ("N s/m", "a soft attachment's damper"),
    "scene/*/implicit.newton_iterations": ("", "linearized solves per step (1 is Baraff and "
                                               "Witkin's step)"),
    "scene/*/implicit.cg_tolerance": ("", "relative residual at which each conjugate-gradient "
                                          "solve stops"),
    "scene/*/implicit.cg_max_iterations": ("", "most conjugate-gradient iterations per solve"),
    "scene/*/implicit.preconditioner": ("", "\"two_level\" (block Jacobi and a coarse space of "
                                            "aggregates) or \"block_jacobi\" alone"),
    "*/*/type": ("", "which kind of body or terrain the table describes"),
    "bodies/*/thickness": ("m", "how far the surface is kept from other surfaces (a pair keeps "
                                "the mean of its two bodies' thicknesses)"),
    "bodies/cloth/thickness": ("m", "as the cube's; left out: 0.02, or a quarter of the particle "
                                    "spacing where that is less"),
    "bodies/*/self_collision": ("", "the surface also pushes on itself"),
    "bodies/*/friction": ("", "kinetic Coulomb coefficient against other surfaces"),
    "bodies/*/static_friction": ("", "a contact sticks while its friction stays within this "
                                     "times its normal push"),
    "bodies/*/restitution": ("", "share of the approach speed a contact with another surface "
                                 "gives back"),
    "bodies/*/structural": ("", "springs to the +x, +y, +z lattice neighbours"),
    "bodies/*/shear": ("", "springs along the 10 face and body diagonals"),
    "bodies/*/bend": ("", "springs that skip one particle (+2x, +2y, +2z)"),
    "bodies/cloth/structural": ("", "springs to the next particle along each grid line"),
    "bodies/cloth/shear": ("", "springs along the grid's diagonals"),
    "bodies/cloth/bend": ("", "springs that skip one particle along each grid line"),
    "bodies/*/face_springs": ("", "add long springs from each face particle to the opposite face"),
    "bodies/*/face": ("", "the face springs' stiffness and damping"),
    "*/*/*.ks": ("N/m", f"spring stiffness ({SPRING_KINDS}: a kind with ks = kd = 0 is not built)"),
    "*/*/*.kd": ("N s/m", "damping along the spring"),
    "bodies/*/particles_per_edge": ("", "N: the cube has N³ particles"),
    "bodies/cloth/particles_per_edge": ("", "N: the cloth has N x N particles"),
    "bodies/*/edge_length": ("m", "length of an edge"),
    "bodies/*/particle_mass": ("kg", "mass of each particle"),
    "bodies/cube/position": ("m", "where particle (N//2, N//2, N//2) starts"),
    "bodies/cloth/position": ("m", "centre of the sheet; with a `file`, added to the mesh's "
                                   "coordinates after scale and rotation"),
    "bodies/mesh/position": ("m", "added to the mesh's coordinates after scale and rotation"),
    "bodies/*/velocity": ("m/s", "initial velocity of every particle"),
    "bodies/*/rotation_degrees": ("degrees", "initial rotation about `rotation_axis`"),
    "bodies/*/rotation_axis": ("", "axis of that rotation (any length but zero)"),
    "bodies/*/pinned": ("", "particle numbers held fixed in space"),
    "bodies/*/pins": ("", "the `[[bodies.pins]]` tables: particles chosen by `particles`, "
                          "`region` or `group`, held, moved by a `motion`, made to `follow` a "
                          "terrain, or soft with `stiffness` and `damping` "
                          "([Scene files](../scene-files.md#pins-that-move))"),
    "bodies/cloth/pinned": ("", "`corners`, `none`, `edge` (the +z edge), `edge+z`, `edge-z`, "
                                "`edge+x`, `edge-x`, or a list of particle numbers"),
    "bodies/cloth/file": ("", "a triangle or quad mesh (OBJ, STL, PLY, OFF, GLB, GLTF) to be "
                              "the cloth instead of the grid; relative to the scene file's "
                              "folder; `builtin:NAME` is a mesh installed with springsim"),
    "bodies/cloth/scale": ("", "factor on the file's coordinates"),
    "bodies/cloth/material": ("", "a material per area instead of `particle_mass` and per-kind "
                                  "`ks`, `kd`: the same cloth at any resolution"),
    "bodies/cloth/material.density": ("kg/m²", "mass per area, shared among each face's corners"),
    "bodies/cloth/material.stretch": ("N/m", "stiffness per unit strain along the edges"),
    "bodies/cloth/material.shear": ("N/m", "stiffness per unit strain across quad diagonals"),
    "bodies/cloth/material.bend": ("N/m", "each bend spring's stiffness"),
    "bodies/cloth/material.stretch_damping": ("N s/m", "damping per unit strain rate, edges"),
    "bodies/cloth/material.shear_damping": ("N s/m", "damping per unit strain rate, diagonals"),
    "bodies/cloth/material.bend_damping": ("N s/m", "each bend spring's damping"),
    "bodies/cloth/pins": ("", "the `[[bodies.pins]]` tables: more pinned particles, each "
                              "chosen one way"),
    "bodies/*/pins.N.particles": ("", "particle numbers to pin"),
    "bodies/*/pins.N.region": ("", "a box; the particles that start inside it are pinned"),
    "bodies/*/pins.N.region.min": ("m", "the box's lowest corner"),
    "bodies/*/pins.N.region.max": ("m", "the box's highest corner"),
    "bodies/*/pins.N.group": ("", "an OBJ group (`g` or `o` name) of the body's mesh file"),
    "bodies/*/pins.N.motion": ("", "moves the pinned particles as a function of time (the "
                                   "keys below)"),
    "bodies/*/pins.N.follow": ("", '"terrains.N": the pinned particles move with that terrain'),
    "bodies/*/pins.N.stiffness": ("N/m", "a soft pin: a spring to the pin's place; left out, "
                                         "the pin is hard"),
    "bodies/*/pins.N.damping": ("N s/m", "a soft pin's damper"),
    "bodies/cloth/width": ("m", "size along the sheet's local x axis"),
    "bodies/cloth/height": ("m", "size along the sheet's local z axis"),
    "bodies/*/drag": ("N s/m", "the body's own viscous drag, added to the scene's `drag`"),
    "bodies/balls/balls": ("", "the `[[bodies.balls]]` tables, one per ball"),
    "bodies/balls/balls.N.position": ("m", "centre of the ball"),
    "bodies/balls/balls.N.velocity": ("m/s", "initial velocity"),
    "bodies/balls/balls.N.radius": ("m", "radius"),
    "bodies/balls/balls.N.mass": ("kg", "mass"),
    "bodies/balls/ball_restitution": ("", "restitution between two balls"),
    "bodies/balls/particle_restitution": ("", "restitution between a ball and a particle"),
    "bodies/balls/particle_friction": ("", "Coulomb friction between a ball and a particle"),
    "bodies/balls/position_correction": ("", "share of a penetration removed each step"),
    "*/mesh/file": ("", "the mesh (OBJ, STL, PLY, OFF, GLB, GLTF); relative to the scene file's "
                        "folder; `builtin:NAME` is a mesh installed with springsim "
                        "(`builtin:torus.obj`, `builtin:stairs.obj`)"),
    "bodies/mesh/spacing": ("m", 'distance between lattice particles, or "auto": the spacing '
                                 "(three significant digits) for about `particles` particles"),
    "bodies/mesh/particles": ("", 'the particle budget of spacing = "auto"'),
    "*/mesh/scale": ("", "factor on the file's coordinates"),
    "*/mesh/rotation_degrees": ("degrees", "rotation about the file's origin, after scaling"),
    "*/mesh/rotation_axis": ("", "axis of that rotation (any length but zero)"),
    "terrains/mesh/position": ("m", "added to the mesh's coordinates after scale and rotation"),
    "terrains/mesh/resolution": ("", "cells of the signed distance grid along the mesh's longest "
                                     "side"),
    "terrains/*/restitution": ("", "share of the normal speed kept after an impact"),
    "terrains/*/friction": ("", "Coulomb friction coefficient"),
    "terrains/*/epsilon": ("m", "contact band: a particle closer than this touches"),
    "terrains/*/motion": ("", "moves the terrain as a function of time: `keyframes` (`time`, "
                              "`position`, `rotation_degrees`, `rotation_axis`) with "
                              "`interpolation`, or `velocity` and `angular_velocity`, about "
                              "`pivot` ([Scene files](../scene-files.md#moving-terrains))"),
    "terrains/*/point": ("m", "a point of the plane"),
    "terrains/*/normal": ("", "normal towards the free side (any length but zero)"),
    "terrains/sphere/center": ("m", "centre; bodies collide with its outside"),
    "terrains/bowl/center": ("m", "centre; bodies stay inside it"),
    "terrains/*/radius": ("m", "radius"),
    "terrains/*/mass": ("kg", "kept for the course framework; unused"),
    "scene/*/wind.velocity": ("m/s", "the air's constant velocity"),
    "scene/*/wind.keyframes": ("", "the `[[wind.keyframes]]` tables: the air's velocity at "
                                   "given times, linear between them and held outside them"),
    "scene/*/wind.keyframes.N.time": ("s", "the keyframe's time (required, increasing)"),
    "scene/*/wind.keyframes.N.velocity": ("m/s", "the air's velocity at that time"),
    "scene/*/wind.density": ("kg/m³", "the air's density"),
    "scene/*/wind.drag": ("", "drag coefficient of the air's motion across a surface"),
    "scene/*/wind.friction": ("", "friction coefficient of the air's motion along a surface"),
    "scene/*/wind.gusts": ("", "seeded turbulence, the same in every run"),
    "scene/*/wind.gusts.strength": ("", "gust speed as a share of the mean wind speed (m/s in "
                                        "still air)"),
    "scene/*/wind.gusts.length": ("m", "the size of a gust"),
    "scene/*/wind.gusts.seed": ("", "the seed of the gusts' random field"),
}
MOTION_NOTES = {
    "motion.keyframes": ("", "the `[[...motion.keyframes]]` tables: poses at given times"),
    "motion.keyframes.N.time": ("s", "the keyframe's time (required, increasing)"),
    "motion.keyframes.N.position": ("m", "displacement at that time"),
    "motion.keyframes.N.rotation_degrees": ("degrees", "rotation at that time, about "
                                                       "`rotation_axis` through the pivot"),
    "motion.keyframes.N.rotation_axis": ("", "axis of that rotation (any length but zero)"),
    "motion.interpolation": ("", '"linear", or "smooth": a C1 cubic through the keyframes '
                                 "that starts and ends at rest"),
    "motion.velocity": ("m/s", "a constant velocity instead of keyframes"),
    "motion.angular_velocity": ("rad/s", "a constant angular velocity about the pivot"),
    "motion.pivot": ("m", "the point the rotations turn about; left out, the terrain's anchor "
                          "(a sphere's centre, a plane's point) or the pinned particles' centre"),
}
ANIMATION_NOTES = {
    "animation.file": ("", "a point cache (PC2 or MDD, as Blender's and Houdini's exporters "
                           "write them); relative to the scene file's folder"),
    "animation.fps": ("frames/s", "a PC2's frame rate: sample k is at start + k rate / fps "
                                  "(an MDD carries its own times)"),
    "animation.start": ("s", "the time of the cache's first sample"),
}
NOTES |= {"terrains/mesh/animation": ("", "deforms the mesh by a point cache of its file's "
                                          "vertices (file order, the file's frame) "
                                          "([Scene files](../scene-files.md#deforming-terrains))"),
          "bodies/*/pins.N.animation": ("", "moves the pinned particles with a point cache of "
                                            "the body's points (a mesh cloth's file vertices, "
                                            "or the particles)")}
NOTES |= {f"terrains/mesh/{key}": note for key, note in ANIMATION_NOTES.items()}
NOTES |= {f"bodies/*/pins.N.{key}": note for key, note in ANIMATION_NOTES.items()}
NOTES |= {f"terrains/*/{key}": note for key, note in MOTION_NOTES.items()}
NOTES |= {f"bodies/*/pins.N.{key}": note for key, note in MOTION_NOTES.items()}


def group_type_key(scene_key):
    """("bodies", "cube", "structural.ks") for ``bodies.N.structural.ks`` of a cube."""
    parts = scene_key.path.split(".")
    if parts[0] in ("bodies", "terrains") and len(parts) > 2:
        return parts[0], scene_key.owner, ".".join(parts[2:])
    return "scene", "*", scene_key.path


def note_for(scene_key):
    """(unit, meaning) of a key, or None when NOTES has no line for it."""
    group, kind, key = group_type_key(scene_key)
    last = key.rsplit(".", 1)[-1]
    for candidate in (f"{group}/{kind}/{key}", f"{group}/*/{key}", f"*/{kind}/{key}",
                      f"*/*/{key}", f"*/*/*.{last}"):
        if candidate in NOTES:
            return NOTES[candidate], candidate
    return None


# --- the allowed values, from the validation itself --------------------------------------------

def base_scene(group: str, kind: str):
    """A valid scene holding one ``kind`` of body or terrain (as item 0 of its list)."""
    from springsim.presets import MESHES
    from springsim.scene import Scene
    from springsim.scenefile import BODY_TYPES, TERRAIN_TYPES
    from springsim.bodies.cube import Cube

    if group == "bodies":
        body = BODY_TYPES[kind]()
        if kind == "mesh":   # a unit box: checking a mesh body builds its lattice
            body.file, body.spacing = str(unit_box_file()), 0.25
        return Scene(bodies=[body])
    if group == "terrains":
        terrain = TERRAIN_TYPES[kind]()
        if kind == "mesh":
            terrain.file = str(MESHES / "stairs.obj")
        return Scene(bodies=[Cube()], terrains=[terrain])
    return Scene(bodies=[Cube()])


@functools.lru_cache(maxsize=1)
def unit_box_file() -> Path:
    """A closed 1 m box as an OBJ file (eight corners, twelve outward-wound triangles)."""
    import tempfile

    corners = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    faces = [(1, 2, 4), (1, 4, 3), (5, 7, 8), (5, 8, 6), (1, 5, 6), (1, 6, 2),
             (3, 4, 8), (3, 8, 7), (1, 3, 7), (1, 7, 5), (2, 6, 8), (2, 8, 4)]
    path = Path(tempfile.mkdtemp(prefix="springsim-docs-")) / "box.obj"
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners)
                    + "".join(f"f {a} {b} {c}\n" for a, b, c in faces))
    return path


def probes(scene_key):
    """Values that a check may refuse, for a key of this kind and default: first one of the wrong
    kind (whose message says what kind the key takes), then out-of-range candidates."""
    kind, default = scene_key.kind, scene_key.default
    if kind == "number":
        return ["text", -1.0, 0.0, 2.0, 20.0, 1e7]
    if kind == "whole number":
        return [1.5, -1, 0, 1, 2, 3]
    if kind == "boolean":
        return ["text"]
    if kind == "string":
        return [1, "no-such-value"]
    if kind == "array of whole numbers":
        return [["text"], [-1]]
    if kind.startswith("array of") and kind.endswith("numbers"):
        return [["text"], [0.0] * len(default)]
    if kind == "string or array":
        return [1.5, "no-such-value", [-1]]
    return []


def allowed_messages(scene_key) -> list[str]:
    """The distinct messages the validation gives for this key's probe values, in probe order."""
    from springsim.errors import SceneError
    from springsim.scenefile import set_path

    group, kind, _ = group_type_key(scene_key)
    scene = base_scene(group, kind)
    concrete = scene_key.path.replace(".N.", ".0.")
    parts, values = concrete.split("."), probes(scene_key)
    if scene_key.path.endswith(".type"):   # a type is said by a whole new table
        parts, values = parts[:-1], [{"type": "no-such-type"}]
    messages = []
    for value in values:
        try:
            candidate = set_path(copy.deepcopy(scene), parts, value, "", concrete)
            candidate.validate()
        except SceneError as error:
            if error.key == concrete or error.key.startswith(concrete + "."):
                # a path in a message is this machine's: say what it stands for
                text = error.allowed.replace(str(Path.cwd()), "the current folder")
                if text not in messages:
                    messages.append(text)
    return messages


# --- the pages ---------------------------------------------------------------------------------



def _section_of(scene_key) -> tuple[str, str]:
    group, kind, _ = group_type_key(scene_key)
    if group == "scene":
        return "scene", "Top level"
    table = "[[bodies]]" if group == "bodies" else "[[terrains]]"
    return f"{group}/{kind}", f'{table} with `type = "{kind}"`'


def _default_text(value) -> str:
    from springsim.scenefile import toml_value

    if value is None:
        return "see meaning"
    if dataclasses.is_dataclass(value):
        return f"`{toml_value(value)}`"
    if isinstance(value, list) and value and dataclasses.is_dataclass(value[0]):
        return f"{len(value)} tables (`springsim scenes` shows them)"
    if value == [] and not isinstance(value, tuple):
        return "none"
    return f"`{toml_value(value)}`"


@functools.lru_cache(maxsize=1)
def scene_reference_markdown() -> str:
    from springsim.scenefile import scene_keys

    lines = [
        "# Scene-file reference",
        "",
        "<!-- Generated by docs/hooks/reference.py at every build: do not edit. -->",
        "",
        "Every key a scene file (or `--set`) accepts, generated from the code at every build of",
        "this site: the keys are those the scene-file reader accepts, and the *allowed* column is",
        "what the validation answers when the key is given a value of the wrong kind or out of",
        "range (each probed in a scene that is valid otherwise), so it cannot drift from what the",
        "code accepts. `N` stands for a list index (`bodies.0`, `bodies.1`, ...). How the tables",
        "fit together, with examples, is in [Scene files](../scene-files.md). Mesh keys are",
        "probed with a 1 m box as the body's mesh and the shipped stairs as the terrain's, so",
        "their numbers (a suggested spacing, the last particle number) are those of these meshes.",
        "",
        "A key that is left out keeps its default. Every value is also checked for size before",
        "anything is built (a scene whose model would not fit in memory is refused).",
    ]
    current = None
    for scene_key in scene_keys():
        section, title = _section_of(scene_key)
        if section != current:
            current = section
            lines += ["", f"## {title}", "",
                      "| key | kind | default | unit | meaning | allowed (from the validation) |",
                      "|---|---|---|---|---|---|"]
        found = note_for(scene_key)
        unit, meaning = found[0] if found else ("", "")
        allowed = "; ".join(allowed_messages(scene_key)) or "any value of its kind"
        lines.append(f"| `{scene_key.path}` | {scene_key.kind} | "
                     f"{_default_text(scene_key.default)} | {unit} | {meaning} | "
                     f"{_cell(allowed)} |")
    return "\n".join(lines) + "\n"


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


@functools.lru_cache(maxsize=1)
def cli_reference_markdown() -> str:
    from springsim.cli import build_parser

    parser = build_parser()
    lines = [
        "# Command-line reference",
        "",
        "<!-- Generated by docs/hooks/reference.py at every build: do not edit. -->",
        "",
        "Every command and option of `springsim`, generated from the command line's own parsers",
        "at every build of this site (`springsim COMMAND --help` prints the same). Errors are one",
        "line naming the key, the value and what is allowed; exit codes: 0 done, 2 bad input,",
        "3 the simulation diverged, 4 no window or headless renderer, 5 a file could not be",
        "written, 130 Ctrl-C, 143 SIGTERM.",
        "",
        "## springsim",
        "",
        parser.description or "",
        "",
        *_option_table(parser),
    ]
    for name, sub in subcommands(parser).items():
        lines += ["", f"## springsim {name}", "", sub.description or "", "",
                  f"```\n{sub.format_usage().strip()}\n```", "", *_option_table(sub)]
    return "\n".join(lines) + "\n"


def subcommands(parser) -> dict:
    """{name: parser} of every subcommand."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def documented_actions(parser):
    return [action for action in parser._actions
            if not isinstance(action, argparse._SubParsersAction)]


def _option_table(parser) -> list[str]:
    rows = ["| argument | meaning | default |", "|---|---|---|"]
    for action in documented_actions(parser):
        if action.option_strings:
            metavar = ""
            if action.nargs != 0:
                metavar = " " + (action.metavar or action.dest.upper())
            names = ", ".join(f"`{option}{metavar}`" for option in action.option_strings)
        else:
            names = f"`{action.metavar or action.dest}`"
        text = (action.help or "").replace("%(default)s", str(action.default))
        if action.choices:
            text += " (one of " + ", ".join(f"`{c}`" for c in action.choices) + ")"
        default = ""
        if action.default not in (None, False, argparse.SUPPRESS) and action.nargs != 0:
            default = f"`{action.default}`"
        if action.required:
            default = "required"
        rows.append(f"| {names} | {_cell(text)} | {_cell(default)} |")
    return rows


def gallery_markdown() -> str:
    from springsim.presets import PRESETS

    lines = ["# Gallery", "",
             "<!-- Generated by docs/hooks/reference.py at every build: do not edit. -->", "",
             "Every built-in scene, simulated and drawn headless by "
             "`.venv/bin/python scripts/make_gallery.py` (the first 3 s of each, or the whole "
             "scene where shorter): an animation and its last frame. Run one yourself with "
             "`springsim run NAME`, watch it with `springsim view NAME`, or write it out as a "
             "scene file with `springsim scenes NAME`."]
    for name, (_, description) in PRESETS.items():
        lines += ["", f"## {name}", "", description[0].upper() + description[1:] + ".", "",
                  f"![{name}, animated](images/gallery-{name}.gif) "
                  f"![{name}, last frame](images/gallery-{name}.png)"]
    return "\n".join(lines) + "\n"
