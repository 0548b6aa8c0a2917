"""No import cycle between the modules, nor between the packages, of src/ (scripts/code_measures.py
prints them with the other measures, which are not asserted here). Oracle: the import graph read
from the AST of every module, imports that run when a module loads only, and Tarjan's strongly
connected components; the rules are checked on a small package written for the test first."""
import importlib.util
from pathlib import Path

import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "code_measures.py"

@pytest.fixture(scope="module")
def measures():
    spec = importlib.util.spec_from_file_location("code_measures", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def write(root: Path, files: dict) -> Path:
    for name, text in files.items():
        path = root / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return root


def test_the_cycle_finder_finds_a_cycle_and_its_path(measures):
    assert measures.cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == \
        [["a", "b", "c", "a"]]
    assert measures.cycles({"a": {"b"}, "b": set()}) == []
    # one component, two cycles through a: the shortest is the path reported
    assert measures.cycles({"a": {"b", "c"}, "b": {"a"}, "c": {"d"}, "d": {"a"}}) == \
        [["a", "b", "a"]]


def test_only_imports_that_run_at_load_count(measures, tmp_path):
    """A package ``p`` whose modules import each other inside a function and under
    TYPE_CHECKING (no cycle there), and two subpackages whose modules import each other at load
    (a cycle between the modules and between the packages)."""
    source = write(tmp_path, {
        "p/__init__.py": "",
        "p/a.py": "from . import b\nTYPE_CHECKING = False\nif TYPE_CHECKING:\n"
                  "    from .c import thing\n",
        "p/b.py": "import p.c\n\ndef late():\n    from . import a\n",
        "p/c.py": "try:\n    from .x.one import value\nexcept ImportError:\n    pass\n",
        "p/x/__init__.py": "", "p/x/one.py": "from ..y import two\nvalue = 1\n",
        "p/y/__init__.py": "", "p/y/two.py": "from ..x.one import value as first\n"
                                             "class Holder:\n    from ..x import one\n",
        "p/y/three.py": "from p.x import one\n"})
    modules = measures.read_modules(source)
    graph = measures.module_graph(modules)
    assert graph["p.a"] == {"p.b"}                  # not c: under TYPE_CHECKING
    assert graph["p.b"] == {"p.c"}                  # not a: inside a function
    assert graph["p.c"] == {"p.x.one"}              # under try
    assert graph["p.x.one"] == {"p.y.two"}          # a name of a package that is a module
    assert graph["p.y.two"] == {"p.x.one"}          # a class body runs at load
    assert graph["p.y.three"] == {"p.x.one"}
    assert measures.cycles(graph) == [["p.x.one", "p.y.two", "p.x.one"]]
    assert measures.package_cycles(modules, graph) == [(1, ["p.x", "p.y", "p.x"])]


def test_no_import_cycle_between_modules(measures):
    modules = measures.read_modules()
    graph = measures.module_graph(modules)
    # the graph was read: the kinds' files and the world's imports are in it
    assert "springsim.terrains.display" in graph["springsim.terrains.plane"]
    assert "springsim.terrains" in graph["springsim.world"]
    assert measures.cycles(graph) == []


def test_no_import_cycle_between_packages(measures):
    modules = measures.read_modules()
    graph = measures.module_graph(modules)
    assert measures.package_components(modules, graph) == []


def test_no_terrain_module_imports_the_renderer_or_the_gradients(measures):
    """A terrain kind is one file that the renderer, the exporters and the gradients read; none
    of its modules reads them back, even inside a function."""
    import ast

    for path in (SCRIPT.parent.parent / "src" / "springsim" / "terrains").glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([node.module or ""] if isinstance(node, ast.ImportFrom)
                     else [alias.name for alias in node.names] if isinstance(node, ast.Import)
                     else [])
            for name in names:
                assert not name.removeprefix("springsim.").startswith(
                    ("render", "gradients", "export")), (path.name, name)
