"""`springsim docs`: build the documentation site if needed and serve it on this machine."""
import sys
from pathlib import Path

NAME = "docs"
HELP = ("build the documentation (MkDocs, the docs extra) if it is missing or older than its "
        "sources, and serve it locally until Ctrl-C")

# The site is built from a source checkout: mkdocs.yml and docs/ beside src/springsim.
ROOT = Path(__file__).resolve().parents[3]


def add_arguments(parser) -> None:
    parser.add_argument("--port", type=int, default=8000,
                        help="TCP port to serve on; 0 picks a free one (default: 8000)")
    parser.add_argument("--host", default="127.0.0.1",
                        help="address to serve on (default: 127.0.0.1, this machine only)")
    parser.add_argument("--site-dir", metavar="DIR",
                        help="where the built site goes "
                             "(default: ~/.cache/springsim/site, outside the checkout)")
    parser.add_argument("--rebuild", action="store_true",
                        help="build the site even when it is newer than its sources")


def run(args) -> int:
    from ..errors import require

    config = ROOT / "mkdocs.yml"
    require(config.is_file(), "docs", str(ROOT),
            "needs a source checkout of springsim (mkdocs.yml and docs/ beside src/); "
            "an installed package carries no documentation sources")
    require(0 <= args.port <= 65535, "--port", args.port, "must be a TCP port in [0, 65535]")
    site = Path(args.site_dir).expanduser() if args.site_dir else default_site_dir()
    if args.rebuild or is_stale(site):
        build_site(config, site)
    return serve(site, args.host, args.port)


def default_site_dir() -> Path:
    import os

    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "springsim" / "site"


def sources() -> list[Path]:
    """The files the site is built from: a change to any makes the built site stale."""
    files = [ROOT / "mkdocs.yml", ROOT / "CHANGELOG.md"]
    files += [path for path in (ROOT / "docs").rglob("*") if path.is_file()]
    files += [path for path in (ROOT / "src" / "springsim").rglob("*.py")]   # API pages
    return files


def is_stale(site: Path) -> bool:
    index = site / "index.html"
    if not index.is_file():
        return True
    built = index.stat().st_mtime
    return any(path.stat().st_mtime > built for path in sources())


def build_site(config: Path, site: Path) -> None:
    import subprocess

    from ..errors import require

    try:
        import mkdocs  # noqa: F401  (only to say what is missing, in one line)
    except ImportError:
        require(False, "docs", "mkdocs", "is not installed: install the docs extra, "
                "pip install -e '.[docs]' (./test.sh and ./run.sh install it)")
    print(f"springsim docs: building the site into {site} ...", file=sys.stderr, flush=True)
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--quiet", "--config-file",
                           str(config), "--site-dir", str(site)], cwd=ROOT,
                          env=_environment(), capture_output=True, text=True)
    require(done.returncode == 0, "docs", "mkdocs build",
            "failed: " + (done.stderr.strip().splitlines() or ["no message"])[-1])


def _environment() -> dict:
    """mkdocs's environment, with this springsim first on the path (the hook imports it)."""
    import os

    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    source = str(ROOT / "src")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [source, env.get("PYTHONPATH")]))
    return env


def serve(site: Path, host: str, port: int) -> int:
    import functools
    from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer

    from ..errors import require

    class Quiet(SimpleHTTPRequestHandler):
        def log_message(self, format, *args):   # one line at start, not one per request
            pass

    handler = functools.partial(Quiet, directory=str(site))
    try:
        server = ThreadingHTTPServer((host, port), handler)
    except OSError as error:
        require(False, "--port", port, f"cannot be served on {host}: {error.strerror}; "
                "give another --port (0 picks a free one)")
    with server:
        bound_host, bound_port = server.server_address[:2]
        print(f"springsim docs: serving {site} at http://{bound_host}:{bound_port}/ "
              "(Ctrl-C stops)", flush=True)
        server.serve_forever()
    return 0
