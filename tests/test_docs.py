"""The documentation cannot drift: the site builds with ``mkdocs build --strict``, the generated
references list every scene key and every command-line option the code accepts, and the README
stays a short user's guide. (tests/test_docs_examples.py runs the examples; test_docs_serve.py
`springsim docs`.)"""
import dataclasses
import argparse
import importlib.util
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from test_docs_examples import ROOT, environment

from springsim.errors import SceneError
from springsim.presets import PRESETS
from springsim.scenefile import load_scene, scene_keys, scene_to_toml


def load_hook():
    spec = importlib.util.spec_from_file_location("docs_reference_hook",
                                                  ROOT / "docs" / "hooks" / "reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


hook = load_hook()


def mkdocs_build(config_dir: Path, site: Path, tmp_path: Path):
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--config-file",
                           str(config_dir / "mkdocs.yml"), "--site-dir", str(site)],
                          cwd=config_dir, env=environment(tmp_path), capture_output=True,
                          text=True, timeout=600)


# --- the site ----------------------------------------------------------------------------------

@pytest.mark.slow   # a whole MkDocs build
def test_site_builds_strict(tmp_path):
    pytest.importorskip("mkdocs", reason="the docs extra (./test.sh installs it)")
    done = mkdocs_build(ROOT, tmp_path / "site", tmp_path)
    assert done.returncode == 0, done.stderr[-4000:]
    site = tmp_path / "site"
    reference = (site / "guide" / "scene-reference" / "index.html").read_text()
    assert "bodies.N.particles_per_edge" in reference
    api = (site / "api" / "simulation" / "index.html").read_text()
    assert "save_state" in api and "advance" in api   # mkdocstrings read the docstrings
    for name in PRESETS:                               # the gallery has every built-in scene
        assert (site / "images" / f"gallery-{name}.gif").is_file(), name


@pytest.mark.slow   # a whole MkDocs build
def test_strict_build_fails_on_a_broken_link(tmp_path):
    """The configuration really is strict: a page linking to a missing page stops the build
    (so the passing build above means every link and reference resolves)."""
    pytest.importorskip("mkdocs", reason="the docs extra (./test.sh installs it)")
    copy = tmp_path / "copy"
    copy.mkdir()
    for name in ("mkdocs.yml", "CHANGELOG.md"):
        shutil.copy(ROOT / name, copy / name)
    shutil.copytree(ROOT / "docs", copy / "docs", ignore=shutil.ignore_patterns("*.gif"))
    (copy / "src").symlink_to(ROOT / "src")
    for name in PRESETS:   # GIFs left out to keep the copy small; empty stand-ins link fine
        (copy / "docs" / "images" / f"gallery-{name}.gif").write_bytes(b"")
    for name in ("cube.gif", "cloth.gif", "torus.gif"):
        (copy / "docs" / "images" / name).write_bytes(b"")
    page = copy / "docs" / "getting-started.md"
    page.write_text(page.read_text() + "\nSee [the missing page](no-such-page.md).\n")
    done = mkdocs_build(copy, tmp_path / "site", tmp_path)
    assert done.returncode != 0
    assert "no-such-page.md" in done.stderr


# --- the scene-file reference -------------------------------------------------------------------

def reference_sections() -> dict:
    """{section title: text} of the generated scene-file reference."""
    text = hook.scene_reference_markdown()
    parts = re.split(r"^## (.+)$", text, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2]))


def test_scene_reference_lists_every_key_the_validation_accepts():
    sections = reference_sections()
    keys = scene_keys()
    assert len(keys) > 100
    for key in keys:
        _, title = hook._section_of(key)
        assert title in sections, title
        assert f"| `{key.path}` |" in sections[title], f"{key.owner} {key.path} not documented"


def flattened_paths(table, prefix=""):
    """Every dotted key of a parsed scene file, list indices as N."""
    for name, value in table.items():
        path = f"{prefix}{name}"
        yield path
        if isinstance(value, dict):
            yield from flattened_paths(value, path + ".")
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                yield from flattened_paths(item, path + ".N.")


@pytest.mark.parametrize("name", list(PRESETS))
def test_every_key_of_a_written_out_scene_is_in_the_reference(name):
    """An independent route to the keys: each built-in scene written out in full (every key the
    writer knows) and read back; each of its keys is a documented key."""
    documented = {key.path for key in scene_keys()} | {"name"}
    table = tomllib.loads(scene_to_toml(load_scene(name)))
    for path in flattened_paths(table):
        assert path in documented, f"{name}: {path} is in the scene file but not the reference"


def in_a_list_empty_by_default(scene, path):
    node, parts = scene, path.split(".")
    for at, part in enumerate(parts):
        if node is None:   # an unset table (the wind): its lists are empty
            return "N" in parts[at:]
        if part == "N":
            if not node:
                return True
            node = node[0]
        elif dataclasses.is_dataclass(node):
            node = getattr(node, part)
        else:
            return False
    return False


def test_scene_reference_rejects_nothing_it_lists():
    """Each listed key is accepted: set to its own default by an override, every key passes the
    validation (an unknown key would be refused with 'unknown key')."""
    from springsim.scenefile import apply_override, toml_value

    for key in scene_keys():
        # a mesh's file has no default ("" must be replaced by a file's name)
        if key.default is None or key.path.endswith((".type", "bodies", "terrains", ".file")):
            continue
        if ".animation." in key.path:   # a point cache's table is nothing without its file:
            continue                     # tests/test_deforming_terrains.py reads them
        group, kind, _ = hook.group_type_key(key)
        scene = hook.base_scene(group, kind)
        if in_a_list_empty_by_default(scene, key.path):   # a cloth's pins, the wind's keys:
            continue           # tests/test_cloth_mesh.py and test_wind.py read them from files
        concrete = key.path.replace(".N.", ".0.")
        apply_override(scene, f"{concrete}={toml_value(key.default)}").validate()


def test_allowed_column_is_what_the_validation_says():
    """Out-of-range values given through the public route (a built-in scene and an override)
    are refused with a message that the reference quotes for that key."""
    from springsim.scenefile import TYPED_LISTS, type_name

    sections = reference_sections()
    checked = 0
    for scene_name in ("jelly-plane", "cloth-balls", "jelly-torus"):
        scene = load_scene(scene_name)
        places = [("scene", None, "")] + [
            (group, type_name(item, TYPED_LISTS[group][1]), f"{group}.{index}.")
            for group in TYPED_LISTS for index, item in enumerate(getattr(scene, group))]
        for group, kind, prefix in places:
            for key in scene_keys():
                if key.kind != "number" or hook.group_type_key(key)[:2] != (group, kind or "*"):
                    continue
                relative = (key.path.split(".N.", 1)[1] if prefix else key.path).replace(
                    ".N.", ".0.")
                try:
                    load_scene(scene_name, [f"{prefix}{relative}=-1"])
                    continue
                except SceneError as error:
                    if error.key != f"{prefix}{relative}":
                        continue
                    row = next(line for line in sections[hook._section_of(key)[1]].splitlines()
                               if line.startswith(f"| `{key.path}` |"))
                    assert error.allowed in row, (scene_name, key.path, error.allowed)
                    checked += 1
    assert checked > 20


def test_every_key_has_a_unit_and_meaning_and_every_note_a_key():
    used = set()
    for key in scene_keys():
        found = hook.note_for(key)
        assert found is not None, f"docs/hooks/reference.py NOTES has no line for {key.path} " \
                                  f"({key.owner})"
        used.add(found[1])
    assert set(hook.NOTES) == used, f"notes for keys that do not exist: {set(hook.NOTES) - used}"


# --- the command-line reference -----------------------------------------------------------------

def help_options(parser) -> set[str]:
    """The options a command's --help text prints (the text, not the parser's objects)."""
    options = set()
    for line in parser.format_help().splitlines():   # "  -h, --help  ...", "  --set KEY=VALUE"
        if re.match(r"^  -", line):
            options.update(re.findall(r"(?:^|, )(--?[A-Za-z][\w-]*)", line.strip().split("  ")[0]))
    return options


def environment_no_tools():
    import os
    env = dict(os.environ)
    env["PYTHONPATH"] = str(ROOT / "src")
    return env


def test_cli_reference_lists_every_option_of_every_command():
    from springsim.cli import build_parser

    text = hook.cli_reference_markdown()
    sections = dict(zip(*[iter(re.split(r"^## (.+)$", text, flags=re.M)[1:])] * 2))
    parser = build_parser()
    commands = hook.subcommands(parser)
    assert {"run", "render", "docs", "sweep", "view", "export"} <= set(commands)
    for name in ["", *commands]:
        section = sections[f"springsim {name}".strip()]
        options = help_options(commands[name] if name else parser)
        assert options, name
        for option in options:
            assert re.search(rf"`{re.escape(option)}[ `]", section), \
                f"springsim {name} {option} is not in the command-line reference"
        for action in hook.documented_actions(commands[name] if name else parser):
            if not action.option_strings and action.help is not argparse.SUPPRESS:
                assert f"`{action.metavar or action.dest}`" in section, (name, action.dest)


def test_the_command_line_guide_has_a_row_for_every_command():
    from springsim.cli import build_parser

    text = (ROOT / "docs" / "guide" / "command-line.md").read_text()
    table = set(re.findall(r"^\| `springsim ([\w-]+)", text, re.M))
    assert set(hook.subcommands(build_parser())) <= table, \
        sorted(set(hook.subcommands(build_parser())) - table)


# --- generated pages kept in the repository, and links that work in a clone ---------------------

@pytest.mark.parametrize("uri", hook.COMMITTED)
def test_the_committed_reference_is_what_the_code_generates(uri):
    committed = (ROOT / "docs" / uri).read_text(encoding="utf-8")
    assert committed == hook.GENERATED[uri](), (
        f"docs/{uri} is out of date: run `.venv/bin/python docs/hooks/reference.py`")


def test_every_relative_link_of_the_docs_names_a_file_of_the_clone():
    """Read in the clone (GitHub, an editor), a page's links must lead somewhere: every
    relative link of README.md and docs/ names a file that exists (the site's build checks the
    same for the site)."""
    generated_only = set(hook.GENERATED) - set(hook.COMMITTED)
    dead = []
    for page in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.S)
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"^[a-z]+:|^#", target):
                continue                                    # a web address, an anchor
            path = (page.parent / target.split("#")[0]).resolve()
            site_page = path.relative_to(ROOT / "docs").as_posix() \
                if path.is_relative_to(ROOT / "docs") else ""
            if not path.exists() and site_page not in generated_only:
                dead.append(f"{page.relative_to(ROOT)}: {target}")
    assert dead == []


def test_every_api_page_says_where_its_text_is_when_read_in_a_clone():
    """An API page is mkdocstrings directives (`::: NAME`) that only the site's build fills in:
    read in a clone (as getting-started's link to api/simulation.md is), it must still say
    where its text is, the names it documents and the `python -m pydoc` that prints them."""
    import pydoc

    for page in sorted((ROOT / "docs" / "api").glob("*.md")):
        text = page.read_text(encoding="utf-8")
        names = re.findall(r"^::: (\S+)", text, re.M)
        prose = " ".join(line for line in text.splitlines()
                         if not line.startswith((":::", "    "))).replace("  ", " ")
        assert names, page
        for name in names:
            assert pydoc.locate(name) is not None, (page.name, name)
            assert f"`{name}`" in prose, (page.name, name)
        assert f"`python -m pydoc {names[0]}`" in prose, page.name


# --- version, changelog, README -------------------------------------------------------------------

def test_version_is_the_package_version_and_the_changelog_top_release():
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    done = subprocess.run([sys.executable, "-m", "springsim", "--version"], capture_output=True,
                          text=True, env=environment_no_tools())
    assert done.returncode == 0
    assert done.stdout.strip() == f"springsim {pyproject}"
    changelog = (ROOT / "CHANGELOG.md").read_text()
    releases = re.findall(r"^## \[(\d+\.\d+\.\d+)\] - (\d{4}-\d{2}-\d{2})$", changelog, re.M)
    assert releases and releases[0][0] == pyproject


def test_readme_is_a_short_current_guide():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text) < 12_000, len(text)
    assert not re.search(r"\b\d{4}-\d{2}-\d{2}\b", text), "a date in the README"
    assert not re.search(r"\b\d{1,2}:\d{2}\b", text), "a time of day in the README"
    hashes = [word for word in re.findall(r"\b[0-9a-f]{7,40}\b", text)
              if re.search(r"[a-f]", word) and re.search(r"\d", word)]
    assert not hashes, f"commit hashes in the README: {hashes}"
    first_block = re.search(r"```bash\n(.*?)```", text, re.S).group(1).splitlines()
    assert first_block[0].startswith("./run.sh ") and first_block[1].startswith("./test.sh ")
    links = re.findall(r"\]\(([^)#]+)", text)
    assert links
    for target in links:   # the README is read on its own too: every link is a file here
        assert (ROOT / target).is_file(), f"README links to {target}, which does not exist"
