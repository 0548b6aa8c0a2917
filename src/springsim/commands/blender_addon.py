"""`springsim blender-addon OUT.zip`: the Blender extension (src/springsim_blender), ready for
Blender's *Install from Disk*, with the path of this Python inside so that the extension finds
springsim by itself."""
import sys

NAME = "blender-addon"
HELP = ("write the springsim extension for Blender 4.2+ as a zip to install with Edit > "
        "Preferences > Get Extensions > Install from Disk; it runs springsim with this Python")
PACKAGE = "springsim_blender"
PYTHON_FILE = "springsim_python.txt"     # runner.PYTHON_FILE: read by the extension
SUFFIXES = (".py", ".toml")


def add_arguments(parser) -> None:
    parser.add_argument("out", metavar="OUT.zip", help="the zip file to write")
    parser.add_argument("--python", metavar="PATH",
                        help="the Python the extension runs springsim with (default: this one, "
                             f"{sys.executable})")
    parser.add_argument("--quiet", action="store_true", help="print nothing when it works")


def run(args) -> int:
    import os
    import zipfile

    from ..errors import require
    from ..safe_files import atomic_output, check_output_path

    require(args.out.lower().endswith(".zip"), "OUT.zip", args.out,
            "must name a .zip file (Blender installs extensions from zips)")
    check_output_path("OUT.zip", args.out)
    python = os.path.abspath(args.python or sys.executable)
    require(os.path.isfile(python), "--python", args.python, "is not a file")
    files = extension_files()
    with atomic_output(args.out) as raw, zipfile.ZipFile(raw, "w", zipfile.ZIP_DEFLATED) as zip:
        for name, path in files:
            zip.writestr(entry(name), path.read_bytes())
        zip.writestr(entry(PYTHON_FILE), python + "\n")
    if not args.quiet:
        print(f"wrote {args.out}: the springsim extension, running springsim with {python}; "
              "install it in Blender with Edit > Preferences > Get Extensions > Install from "
              "Disk")
    return 0


def entry(name: str):
    """A zip entry with a fixed date: the same sources give the same zip, byte for byte."""
    import zipfile

    info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = 0o644 << 16
    return info


def extension_files() -> list:
    """(name in the zip, path) of the extension's files, manifest at the zip's root."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.find_spec(PACKAGE)
    folder = Path(spec.origin).parent
    return [(path.name, path) for path in sorted(folder.iterdir())
            if path.suffix in SUFFIXES and path.is_file()]
