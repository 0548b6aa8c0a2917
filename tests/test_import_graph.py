"""No import cycles: no springsim module imports, at its top or inside a function, a module that
imports it back (directly or through others). Oracle: the import graph read from the sources,
with Tarjan's strongly connected components; a cycle is a component of more than one module.
The integrators' registry once sat in the package's ``__init__`` that imports every method, each
of which imported ``register`` back from it; and presets -> scene -> scenefile -> presets."""
import ast
import sys
from pathlib import Path

SOURCE = Path(__file__).resolve().parent.parent / "src"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SOURCE).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported_modules(path: Path, modules: dict) -> set:
    """The springsim modules that ``path`` imports anywhere in it (a name imported from a
    package counts as its submodule where there is one)."""
    own = module_name(path)
    package = own if path.name == "__init__.py" else own.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                candidate = f"{target}.{alias.name}"
                found.add(candidate if candidate in modules else target)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return {name for name in found if name in modules and name != own}


def cycles(graph: dict) -> list:
    index, low, stack, on_stack, components = {}, {}, [], set(), []

    def connect(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                components.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in graph:
        if v not in index:
            connect(v)
    return components


def test_the_oracle_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def test_no_springsim_module_imports_one_that_imports_it_back():
    modules = {module_name(path): path for path in SOURCE.rglob("*.py")}
    graph = {name: imported_modules(path, modules) for name, path in modules.items()}
    assert graph["springsim.scene"] and graph["springsim.integrators"]   # the graph was read
    assert cycles(graph) == []
