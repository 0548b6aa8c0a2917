"""The springsim extension in the real client, Blender 4.2 as a module (issue 31).

Each test builds its scene from Python in a fresh Blender (tests/blender_addon_scenes.py, run in a
subprocess so that Blender's state never leaks into other tests), loads the extension with a plain
import + register(), presses Simulate and reads back what Blender shows: every vertex in world
space through the Mesh Cache modifier. Oracles: springsim itself (`springsim run` of the exported
scene folder gives the same positions), the animation Blender evaluates (pins on it), geometry (no
vertex inside the collider, wherever Blender's parents, armatures and modifiers put it), the
direction and order of the wind's push, the file's own vertex count and order, the docs' preset
table, and Blender's own RNA for what the panels draw (a stand-in layout checks every call as
the real UILayout would; bpy in background mode draws no panel).
"""
import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from springsim.cli import main

pytestmark = pytest.mark.external   # the external tier (conftest.py): Blender

HERE = Path(__file__).parent
SOURCE = HERE.parent / "src"
SAME = 1e-6          # m: Blender's take against springsim run's
ON_PATH = 1e-5       # m: a hard pin against the animation it follows (float32 caches)

if importlib.util.find_spec("bpy") is None:
    if os.environ.get("CI") == "true":
        raise RuntimeError("bpy (Blender as a module) is missing: pip install -e '.[blender]'")
    pytest.skip("bpy is not installed here (./test.sh installs it: pip install -e '.[blender]')",
                allow_module_level=True)


def in_blender(scenario: str, folder: Path, **variables) -> dict:
    environment = {**os.environ, **variables,
                   "PYTHONPATH": os.pathsep.join(filter(None, [str(SOURCE),
                                                               os.environ.get("PYTHONPATH")]))}
    environment.pop("SPRINGSIM_PYTHON", None)
    done = subprocess.run([sys.executable, str(HERE / "blender_addon_scenes.py"), scenario,
                           str(folder)], capture_output=True, text=True, timeout=600,
                          env=environment)
    assert done.returncode == 0, done.stderr[-3000:]
    assert "Traceback" not in done.stderr, done.stderr[-3000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def z_up(points) -> np.ndarray:
    """springsim's Y-up coordinates in Blender's Z-up world."""
    points = np.asarray(points, float)
    return np.stack([points[..., 0], -points[..., 2], points[..., 1]], axis=-1)


def y_up(points) -> np.ndarray:
    """Blender's Z-up coordinates in springsim's Y-up world."""
    points = np.asarray(points, float)
    return np.stack([points[..., 0], points[..., 2], -points[..., 1]], axis=-1)


def read_pc2(path) -> np.ndarray:
    count, samples = np.fromfile(path, "<i4", count=8)[[4, 7]]
    return np.fromfile(path, "<f4", offset=32).reshape(samples, count, 3)


@pytest.fixture(scope="module")
def sphere_through(tmp_path_factory) -> tuple[dict, Path]:
    folder = tmp_path_factory.mktemp("sphere")
    return in_blender("sphere_through", folder), folder


def test_a_pinned_grid_takes_a_sphere_through_it_as_springsim_run_does(sphere_through):
    result, folder = sphere_through
    assert result["error"] == ""
    assert result["modifier_last"]
    frames = result["frames"]
    cloth = np.array([result["cloth"][str(f)] for f in frames])
    assert cloth.shape == (len(frames), 400, 3)
    rest = np.asarray(result["rest"])
    pinned = result["pinned"]
    assert len(pinned) == 20
    assert np.abs(cloth[:, pinned] - rest[pinned]).max() <= ON_PATH
    assert np.abs(cloth[-1] - rest).max() > 0.1                   # the rest of it moved
    closest = np.inf
    for frame in frames:
        sphere = np.asarray(result["sphere"][str(frame)])
        centre = np.asarray(result["sphere_centre"][str(frame)])
        # the UV sphere's faces are inside its radius by at most r (1 - cos(pi / 16))
        inscribed = np.linalg.norm(sphere - centre, axis=1).min() * np.cos(np.pi / 16)
        distance = np.linalg.norm(cloth[frame - 1] - centre, axis=1)
        assert distance.min() >= inscribed - 1e-3, frame
        closest = min(closest, distance.min() - inscribed)
    assert closest < 0.03                                          # the sphere met the cloth
    # the exported folder on the command line: the same positions
    exported = folder / "exported"
    take = exported / "take.pc2"
    assert main(["run", str(exported / "scene.toml"), "--fps", "24.0", "--quiet",
                 "--out", str(exported / "take.npz"), "--export", str(take)]) == 0
    expected = z_up(read_pc2(take))
    assert expected.shape == cloth.shape
    assert np.abs(cloth - expected).max() <= SAME


def test_the_take_survives_save_and_reopen_and_free_removes_it(sphere_through):
    result, _ = sphere_through
    last = np.asarray(result["cloth"][str(result["frames"][-1])])
    assert np.array_equal(np.asarray(result["reopened"]), last)
    assert result["after_free"] == {"modifiers": [], "cache_exists": False,
                                    "folder_exists": False}


def test_a_cloth_pinned_to_a_moving_turning_object_follows_it(tmp_path):
    result = in_blender("moving_pin", tmp_path)
    assert result["error"] == ""
    frames, pinned = result["frames"], result["pinned"]
    cloth = np.array([result["cloth"][str(f)] for f in frames])
    animated = np.array([result["animated"][str(f)] for f in frames])
    assert np.abs(animated[-1, pinned] - animated[0, pinned]).max() > 0.4   # it did move
    assert np.abs(cloth[:, pinned] - animated[:, pinned]).max() <= ON_PATH
    free = np.setdiff1d(np.arange(cloth.shape[1]), pinned)
    assert np.abs(cloth[-1, free] - animated[-1, free]).max() > 0.05        # and hangs


def test_a_cloth_pinned_to_an_armature_deformed_mesh_follows_the_deformation(tmp_path):
    result = in_blender("armature_pin", tmp_path)
    assert result["error"] == ""
    frames, pinned = result["frames"], result["pinned"]
    cloth = np.array([result["cloth"][str(f)] for f in frames])
    animated = np.array([result["animated"][str(f)] for f in frames])
    moved = np.linalg.norm(animated[-1, pinned] - animated[0, pinned], axis=1)
    assert moved.max() > 0.2 and moved.max() - moved.min() > 0.1     # bent, not moved rigidly
    assert np.abs(cloth[:, pinned] - animated[:, pinned]).max() <= ON_PATH


def test_a_swelling_collider_pushes_the_cloth_and_none_of_it_gets_inside(tmp_path):
    result = in_blender("deforming_collider", tmp_path)
    assert result["error"] == ""
    assert "[terrains.animation]" in result["exported"]
    centre = np.asarray(result["centre"])
    pushed = 0.0
    for frame in result["frames"]:
        cloth = np.asarray(result["cloth"][str(frame)])
        inscribed = result["radius"][str(frame)] * np.cos(np.pi / 16)
        assert np.linalg.norm(cloth - centre, axis=1).min() >= inscribed - 2e-3, frame
        pushed = max(pushed, cloth[:, 1].max())
    assert pushed > 0.01                               # the sphere swelled through y = 0


def test_pin_weights_below_one_are_springs_of_that_share_of_the_pin_stiffness(tmp_path):
    import tomllib

    result = in_blender("soft_pins", tmp_path)
    assert result["error"] == ""
    scene = tomllib.loads((tmp_path / "exported" / "scene.toml").read_text())
    pins = scene["bodies"][0]["pins"]
    assert [pin.get("stiffness") for pin in pins] == [None, 100.0]     # hard, then 0.5 x 200
    assert sorted(pins[0]["particles"]) == sorted(result["hard"])
    assert sorted(pins[1]["particles"]) == sorted(result["soft"])
    rest, last = np.asarray(result["rest"]), np.asarray(result["last"])
    assert np.abs(last[result["hard"]] - rest[result["hard"]]).max() <= ON_PATH
    sag = rest[result["soft"], 2] - last[result["soft"], 2]
    # the soft edge carries about half the cloth's weight (0.3 kg/m^2 x 1 m^2) on 20 springs
    # of 100 N/m: it gives by m g / 2 / (20 k), not more (it is held), not 0 (it is no hard pin)
    expected = 0.3 * 1.0 * 9.81 / 2 / (len(result["soft"]) * 100.0)
    assert 0.5 * expected < sag.mean() < 1.5 * expected


def test_a_wind_field_blows_the_cloth_its_way_harder_with_more_strength(tmp_path):
    result = in_blender("wind", tmp_path)
    push = {}
    for strength in ("0.0", "4.0", "8.0"):
        assert result[strength]["error"] == ""
        push[strength] = np.asarray(result[strength]["last"])[:, 1].mean()   # along +y
    assert push["0.0"] == pytest.approx(0.0, abs=1e-3)      # hanging straight down
    assert 0.01 < push["4.0"] < push["8.0"]


def test_a_jelly_body_from_a_uv_mapped_mesh_lands_on_a_plane_collider(tmp_path):
    result = in_blender("jelly", tmp_path)
    assert result["error"] == ""
    assert result["has_uv"]
    assert result["cache_points"] == result["vertex_count"]
    assert result["cache_samples"] == 30
    first, rest = np.asarray(result["first"]), np.asarray(result["rest"])
    assert np.abs(first - rest).max() <= ON_PATH           # same vertices, same order
    last = np.asarray(result["last"])
    assert last[:, 2].mean() < rest[:, 2].mean() - 0.2       # it fell
    # and lies on the plane, not through it (the surface rides inside the lattice's cells,
    # about 0.1 m apart at 150 particles)
    assert -0.02 < last[:, 2].min() < 0.1


def test_frames_reach_blender_while_the_run_goes_on_and_cancel_keeps_them(tmp_path):
    result = in_blender("streaming", tmp_path)
    assert result["whole"] == 48
    partial = [count for count in result["seen"] if 0 < count < 48]
    assert len(set(partial)) >= 2                        # several partial takes were shown
    assert result["seen"] == sorted(result["seen"])
    assert 5 <= result["kept"] == result["cancelled_at"] < 48
    modal = result["modal"]
    assert modal["answers"] == [["FINISHED"], ["CANCELLED"]]
    assert modal["reports"][0] == "springsim: simulated 48 frames"
    assert modal["reports"][1].startswith("springsim: cancelled; kept the ")


def test_failures_are_one_line_reports_and_blender_keeps_running(tmp_path):
    bare = tmp_path / "bare-python"
    bare.write_text(f'#!/bin/sh\nexec "{sys.executable}" -I -S "$@"\n')
    bare.chmod(0o755)
    result = in_blender("failures", tmp_path)
    assert "no Python at" in result["no_python"] and "pip install springsim" in \
        result["no_python"]
    assert "springsim is not installed in" in result["no_springsim"]
    assert "not manifold" in result["non_manifold"] and "'Fin'" in result["non_manifold"]
    assert result["diverged"].count("\n") == 0
    assert "springsim run:" in result["diverged"] and "diverged" in result["diverged"]
    assert result["after"] == ""
    for message in result.values():
        assert "Traceback" not in message


def test_the_addon_zip_installs_in_blender_and_finds_springsim(tmp_path):
    zip_path = tmp_path / "springsim.zip"
    assert main(["blender-addon", str(zip_path), "--quiet"]) == 0
    code = ("import sys, bpy; bpy.ops.wm.read_factory_settings(use_empty=True); "
            "bpy.ops.extensions.package_install_files(filepath=sys.argv[1], repo='user_default',"
            " enable_on_install=True); import addon_utils; "
            "print(hasattr(bpy.ops.springsim, 'simulate'), hasattr(bpy.types.Scene, 'springsim'), "
            "flush=True); import os; os._exit(0)")
    done = subprocess.run([sys.executable, "-c", code, str(zip_path)], capture_output=True,
                          text=True, timeout=300, env={**os.environ, "HOME": str(tmp_path),
                               "XDG_CACHE_HOME": str(kernel_cache_home())})
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "True True"
    import zipfile
    with zipfile.ZipFile(zip_path) as archive:
        assert archive.read("springsim_python.txt").decode().strip() == \
            os.path.abspath(sys.executable)
        assert "blender_manifest.toml" in archive.namelist()



# --- colliders moved by parents, armatures and modifiers --------------------------------------

@pytest.fixture(scope="module")
def animated_colliders(tmp_path_factory) -> dict:
    return in_blender("animated_colliders", tmp_path_factory.mktemp("colliders"))


def sphere_frames(result, name) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A sphere's centre (F, 3), radius (F,) and vertices (F, V, 3) as Blender evaluated them."""
    sphere, frames = result["spheres"][name], result["frames"]
    return (np.array([sphere["centre"][str(f)] for f in frames]),
            np.array([sphere["radius"][str(f)] for f in frames]),
            np.array([sphere["vertices"][str(f)] for f in frames]))


def read_obj_vertices(path) -> np.ndarray:
    return np.array([[float(v) for v in line.split()[1:4]]
                     for line in Path(path).read_text().splitlines() if line.startswith("v ")])


def keyframed(vertices: np.ndarray, motion: dict, key: dict) -> np.ndarray:
    """springsim's rigid motion at one keyframe: pivot + position + R (x - pivot)."""
    pivot = np.asarray(motion["pivot"])
    axis = np.asarray(key["rotation_axis"], float)
    axis /= np.linalg.norm(axis)
    angle = np.radians(key["rotation_degrees"])
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rotation = np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross
    return pivot + np.asarray(key["position"]) + (vertices - pivot) @ rotation.T


def test_colliders_moved_by_a_parent_an_armature_or_a_modifier_export_as_blender_shows_them(
        animated_colliders):
    import tomllib

    result = animated_colliders
    assert result["error"] == ""
    folder = Path(result["exported"])
    scene = tomllib.loads((folder / "scene.toml").read_text())
    terrains = {Path(t["file"]).stem: t for t in scene["terrains"]}
    assert set(terrains) == {"Carried", "Rigged", "Displaced"}
    # a parent moves the sphere rigidly: keyframes; an armature or a modifier deforms the
    # mesh: a point cache of its evaluated vertices
    assert "motion" in terrains["Carried"] and "animation" not in terrains["Carried"]
    for name in ("Rigged", "Displaced"):
        assert "animation" in terrains[name] and "motion" not in terrains[name]
    frames = result["frames"]
    for name in ("Carried", "Rigged", "Displaced"):
        centre, radius, vertices = sphere_frames(result, name)
        assert centre[-1, 1] - centre[0, 1] > 0.5, name          # Blender moved it through
        if name == "Carried":
            motion = terrains[name]["motion"]
            rest = read_obj_vertices(folder / terrains[name]["file"])
            assert len(motion["keyframes"]) == len(frames)
            exported = np.array([keyframed(rest, motion, key) for key in motion["keyframes"]])
        else:
            exported = read_pc2(folder / terrains[name]["animation"]["file"])
        assert exported.shape == vertices.shape, name
        assert np.abs(exported - y_up(vertices)).max() <= ON_PATH, name
    carried, _, _ = sphere_frames(result, "Carried")
    assert abs(carried[-1, 0] - carried[0, 0]) > 0.05            # the parent's turn swung it
    _, rigged, _ = sphere_frames(result, "Rigged")
    assert rigged[-1] > 1.25 * rigged[0]                          # the bone grew it


def test_colliders_moved_by_a_parent_an_armature_or_a_modifier_push_the_cloth_along(
        animated_colliders):
    result = animated_colliders
    frames, pinned = result["frames"], result["pinned"]
    cloth = np.array([result["cloth"][str(f)] for f in frames])
    assert np.abs(cloth[:, pinned] - cloth[0, pinned]).max() <= ON_PATH
    for name in ("Carried", "Rigged", "Displaced"):
        centre, radius, _ = sphere_frames(result, name)
        inscribed = radius * np.cos(np.pi / 16)      # the faces' least distance from the centre
        gap = np.array([np.linalg.norm(cloth[k] - centre[k], axis=1).min() - inscribed[k]
                        for k in range(len(frames))])
        assert gap.min() >= -2e-3, (name, int(gap.argmin()) + 1)    # never inside it
        assert gap[0] > 0.1 and gap.min() < 0.01, name      # it starts clear, then meets it
        # and carries it along: the cloth nearest it stays in front of it all the way (y up
        # from the cloth's rest at y = 0 to past 0.25 m)
        ahead = [cloth[k, np.linalg.norm(cloth[k] - centre[k], axis=1).argmin(), 1] - centre[k, 1]
                 for k in range(len(frames))]
        assert min(ahead) > 0.5 * radius.min(), name
        assert cloth[-1, :, 1].max() > centre[-1, 1] + radius[-1] > 0.25, name


# --- Turbulence ---------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def turbulence(tmp_path_factory) -> tuple[dict, Path]:
    folder = tmp_path_factory.mktemp("turbulence")
    return in_blender("turbulence", folder), folder


def test_a_turbulence_field_becomes_the_winds_gusts(turbulence):
    import tomllib

    result, _ = turbulence
    wind = {name: tomllib.loads(Path(path).read_text())["wind"]
            for name, path in result["exports"].items()}
    # Wind 4 m/s along Blender's +y (springsim's -z); Turbulence strength 3, size 0.4, seed 7
    assert wind["gusty"]["velocity"] == pytest.approx([0.0, 0.0, -4.0], abs=1e-6)
    assert wind["gusty"]["gusts"] == {"strength": 0.75, "length": 0.4, "seed": 7}
    # Size 0 (Blender's default) is Blender's unscaled noise, features about 1 m
    assert wind["default_size"]["gusts"] == {"strength": 0.75, "length": 1.0, "seed": 7}
    # in still air the strength is m/s, not a share of the wind's speed
    assert wind["still"]["velocity"] == [0.0, 0.0, 0.0]
    assert wind["still"]["gusts"] == {"strength": 3.0, "length": 0.4, "seed": 7}


def test_turbulence_moves_a_hanging_cloth_otherwise_than_the_wind_alone_and_alike_each_run(
        turbulence):
    result, folder = turbulence
    assert result["error"] == ["", "", ""]
    steady, gusty, again = (np.array(list(result[name].values()))
                            for name in ("steady", "gusty", "again"))
    assert np.array_equal(gusty, again)                    # deterministic: seeded gusts
    assert np.array_equal(gusty[0], steady[0])             # the same start...
    assert np.abs(gusty[-1] - steady[-1]).max() > 0.02     # ...another motion
    assert gusty[-1, :, 1].mean() > 0.1                    # the wind still blows it along +y
    # and the gusts are springsim's own: the exported folder on the command line gives the same
    take = folder / "gusty" / "take.pc2"
    assert main(["run", str(folder / "gusty" / "scene.toml"), "--fps", "24.0", "--quiet",
                 "--export", str(take)]) == 0
    assert np.abs(z_up(read_pc2(take)) - gusty).max() <= SAME


# --- panels, presets, an unsaved file's take, Blender's modules ---------------------------------

@pytest.fixture(scope="module")
def interface(tmp_path_factory) -> tuple[dict, Path]:
    folder = tmp_path_factory.mktemp("interface")
    temporary = folder / "tmp"
    temporary.mkdir()
    return in_blender("interface", folder, TMPDIR=str(temporary)), temporary


def shown(panel: dict) -> set:
    assert panel["problems"] == []
    return {item[1] for item in panel["items"] if item[0] in ("prop", "prop_search", "operator")}


def test_each_panel_shows_its_roles_settings_and_buttons(interface):
    panels = interface[0]["panels"]
    buttons = {"springsim.simulate", "springsim.free"}
    material = {"preset", "thickness", "friction"}
    cloth = {"density", "stretch", "shear", "bend", "stretch_damping", "shear_damping",
             "bend_damping", "pin_group"}
    pins = {"pin_stiffness", "pin_damping"}
    body = {"particles", "particle_mass", "spring_ks", "spring_kd"}
    collider = {"restitution", "resolution"}
    assert shown(panels["cloth"]) == {"role"} | material | cloth | pins | buttons
    assert ["prop_search", "pin_group", "ObjectSettings", "vertex_groups"] in \
        panels["cloth"]["items"]                   # chosen among the object's vertex groups
    assert shown(panels["cloth_unpinned"]) == {"role"} | material | cloth | buttons
    assert shown(panels["body"]) == {"role"} | material | body | buttons
    assert shown(panels["collider"]) == {"role", "friction"} | collider | buttons
    assert shown(panels["none"]) == {"role"}
    run = {"integrator", "substeps", "use_frame_range", "gravity", "self_collision", "use_air",
           "springsim.export_scene"} | buttons
    assert shown(panels["scene"]) == run
    assert shown(panels["scene_all"]) == run | {"frame_start", "frame_end", "air_density",
                                                "air_drag"}
    assert ["label", "springsim: simulated 6 frames"] in panels["scene_all"]["items"]
    assert shown(panels["preferences"]) == {"python_path"}
    assert interface[0]["poll"] == {"mesh": True, "empty": False, "nothing": False}
    # the stand-in layout refuses what Blender's would: a wrong property, keyword, operator, icon
    assert len(panels["wrong"]["problems"]) == 4, panels["wrong"]["problems"]


def load_presets():
    spec = importlib.util.spec_from_file_location("_presets", SOURCE / "springsim_blender" /
                                                  "presets.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def documented_presets() -> dict:
    """The numbers of the preset tables in docs/tutorials/blender.md, by preset name."""
    text = (HERE.parent / "docs" / "tutorials" / "blender.md").read_text()
    section = text.split("### Presets", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        row = re.match(r"^\| \*\*(\w+)\*\*[^|]*\|(.*)\|$", line)
        if row:
            rows[row.group(1).upper()] = [float(cell) for cell in row.group(2).split("|")]
    return rows


def test_each_preset_sets_the_documented_numbers(interface):
    result = interface[0]
    presets = load_presets()
    assert set(presets.CLOTH) | set(presets.BODY) == {"SILK", "COTTON", "DENIM", "LEATHER",
                                                      "RUBBER", "JELLY"}
    documented = documented_presets()
    assert documented == {**{name: list(values) for name, values in presets.CLOTH.items()},
                          **{name: list(values) for name, values in presets.BODY.items()}}
    for name, values in presets.CLOTH.items():
        applied = result["applied"][name]         # Blender keeps float32
        assert [applied[key] for key in presets.CLOTH_KEYS] == \
            [float(np.float32(v)) for v in values], name
        assert result["exported"][name] == dict(zip(presets.CLOTH_KEYS, values)), name
    for name, (ks, kd) in presets.BODY.items():
        applied = result["applied"][name]
        assert (applied["spring_ks"], applied["spring_kd"]) == (ks, kd), name
        assert result["exported"][name] == {kind: {"ks": ks, "kd": kd}
                                            for kind in ("structural", "shear", "bend")}, name


def test_an_unsaved_files_take_goes_to_the_temporary_folder_and_free_removes_it(interface):
    result, temporary = interface
    assert result["blend"] == "" and result["error"] == ""
    assert result["tempdir"] == str(temporary)
    folder = f"springsim_{result['pid']}"
    assert result["modifier_path"] == str(temporary / folder / "Scene" / "Cloth.pc2")
    assert result["cache_header"][4:8:3] == [400, 6]            # 400 vertices, 6 frames
    assert [name for name in result["temp_listing"] if "springsim" in name] == [folder]
    assert result["after_free"]["modifiers"] == []
    assert result["after_free"]["cache_exists"] is False
    assert [name for name in result["after_free"]["temp_listing"] if "springsim" in name] == []


def test_simulate_never_imports_springsim_numba_or_scipy_into_blender(interface):
    result = interface[0]
    assert result["findable"]             # springsim could be imported there: it was not
    assert result["error"] == ""
    for modules in (result["before"], result["after"], result["after_free_modules"]):
        assert "springsim_blender.runner" in modules
        assert [name for name in modules if not name.startswith("springsim_blender")] == []


# --- the tutorial's script, as a user runs it ----------------------------------------------------

def tutorial_script() -> str:
    """The script of docs/tutorials/blender.md that a user runs in Blender (its hanging.py)."""
    from test_docs_examples import blocks

    scripts = [block.code for block in blocks(HERE.parent / "docs" / "tutorials" / "blender.md")
               if block.file == "hanging.py"]
    assert len(scripts) == 1
    return scripts[0]


def kernel_cache_home() -> Path:
    """Where this user's compiled kernels are, for a Blender given a fresh home of its own
    (else its springsim compiles every kernel again: minutes)."""
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")


def test_the_tutorials_script_runs_as_written_with_the_extension_installed_from_its_zip(
        tmp_path):
    """Not the test suite's way (import springsim_blender from the checkout, register()), but the
    user's: `springsim blender-addon`, Install from Disk (here its operator), then the script's
    text exactly as the page shows it, in a Blender whose user folder is fresh."""
    zip_path = tmp_path / "springsim.zip"
    assert main(["blender-addon", str(zip_path), "--quiet"]) == 0
    (tmp_path / "hanging.py").write_text(tutorial_script())
    code = ("import json, os, sys, bpy; "
            "bpy.ops.extensions.package_install_files(filepath=sys.argv[1], "
            "repo='user_default', enable_on_install=True); "
            "exec(compile(open('hanging.py').read(), 'hanging.py', 'exec'), {}); "
            "print(json.dumps(sorted(m for m in sys.modules if 'springsim' in m)), flush=True); "
            "os._exit(0)")
    environment = {key: value for key, value in os.environ.items()
                   if key not in ("PYTHONPATH", "SPRINGSIM_PYTHON")}
    done = subprocess.run([sys.executable, "-c", code, str(zip_path)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600,
                          env={**environment, "HOME": str(tmp_path),
                               "XDG_CACHE_HOME": str(kernel_cache_home())})
    assert done.returncode == 0, done.stderr[-3000:]
    assert "Traceback" not in done.stderr, done.stderr[-3000:]
    # Blender's own reports ("STATUS Installed ...", "Info: ...") go to stdout between the
    # script's lines, as Blender prints them when it is run
    printed = [line for line in done.stdout.strip().splitlines()
               if not line.startswith(("STATUS ", "Info: "))]
    assert printed[:2] == ["springsim: simulated 24 frames", "['MESH_CACHE']"], done.stdout
    modules = json.loads(printed[-1])
    # the installed extension ran, not the checkout's package
    assert "bl_ext.user_default.springsim_blender" in modules
    assert "springsim_blender" not in modules
    assert (tmp_path / "hanging" / "scene.toml").is_file()
    assert main(["run", str(tmp_path / "hanging" / "scene.toml"), "--fps", "24", "--quiet",
                 "--out", str(tmp_path / "take.npz")]) == 0
