"""`springsim blender-addon OUT.zip` (issue 31) without Blender: the zip holds the extension with
its manifest at the root and the path of the Python that wrote it; the same sources give the same
bytes; a bad OUT is one line before anything is written."""
import sys
import tomllib
import zipfile
from pathlib import Path

from springsim.cli import main

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "springsim_blender"


def test_the_zip_holds_the_extension_and_this_python(tmp_path):
    first, second = tmp_path / "a.zip", tmp_path / "b.zip"
    assert main(["blender-addon", str(first), "--quiet"]) == 0
    assert main(["blender-addon", str(second), "--quiet"]) == 0
    assert first.read_bytes() == second.read_bytes()
    with zipfile.ZipFile(first) as archive:
        names = set(archive.namelist())
        assert {path.name for path in PACKAGE.glob("*.py")} | {"blender_manifest.toml"} < names
        manifest = tomllib.loads(archive.read("blender_manifest.toml").decode())
        assert archive.read("springsim_python.txt").decode().strip() == sys.executable
    assert manifest["type"] == "add-on" and manifest["blender_version_min"] == "4.2.0"


def test_another_python_can_be_named(tmp_path):
    out = tmp_path / "x.zip"
    assert main(["blender-addon", str(out), "--python", "/usr/bin/env", "--quiet"]) == 0
    with zipfile.ZipFile(out) as archive:
        assert archive.read("springsim_python.txt").decode().strip() == "/usr/bin/env"


def test_a_bad_out_is_one_line_and_writes_nothing(tmp_path, capsys):
    assert main(["blender-addon", str(tmp_path / "addon.tar")]) == 2
    assert main(["blender-addon", str(tmp_path / "missing" / "addon.zip")]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 2 and "must name a .zip" in lines[0] and "does not exist" in lines[1]
    assert list(tmp_path.iterdir()) == []
