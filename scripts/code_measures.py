"""Measures of the code under src/, printed: functions over MAX_PARAMETERS parameters or
MAX_FUNCTION_LINES lines, modules over MAX_MODULE_LINES lines, and import cycles between modules
and between packages, each with its path.

    python scripts/code_measures.py [src folder]

An import counts when it runs as its module is imported: at the module's top, in a class body,
or under a top-level ``if`` or ``try``; not inside a function (that runs at a call, once every
module is loaded), nor under ``if TYPE_CHECKING:`` (never run). ``from a.b import c`` imports
the module a.b.c where there is one, else a.b (importing a.b.c runs a and a.b too, but an edge
to every parent package would make each package's ``__init__`` part of a cycle with all it
imports, which no import order can break).

A module's package is the folder it lies in; the modules directly in the top folder
(src/springsim/*.py) are each their own node in the package graph, as the top folder is the
whole program. Package cycles are looked for at every depth: a package stands for all the
packages under it when its depth is the one looked at (collision for collision/broad_phase at
depth 1). tests/test_code_measures.py asserts that no cycle is found.
"""
import ast
import sys
from collections import defaultdict
from pathlib import Path
from typing import NamedTuple

MAX_PARAMETERS = 12
MAX_FUNCTION_LINES = 80
MAX_MODULE_LINES = 450
SOURCE = Path(__file__).resolve().parent.parent / "src"


class Module(NamedTuple):
    name: str          # dotted: springsim.collision.broad_phase.grid
    package: str       # dotted name of the package it lies in (itself for an __init__)
    path: Path
    tree: ast.Module


def read_modules(source: Path = SOURCE) -> dict:
    """Every module under ``source``, by dotted name."""
    modules = {}
    for path in sorted(source.rglob("*.py")):
        parts = path.relative_to(source).with_suffix("").parts
        is_package = parts[-1] == "__init__"
        name = ".".join(parts[:-1] if is_package else parts)
        package = name if is_package else ".".join(parts[:-1])
        modules[name] = Module(name, package, path, ast.parse(path.read_bytes(), str(path)))
    return modules


def load_time_imports(tree: ast.Module):
    """The Import and ImportFrom nodes that run when the module is imported (module doc)."""
    pending = list(tree.body)
    while pending:
        node = pending.pop(0)
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        elif isinstance(node, ast.If) and _is_type_checking(node.test):
            pending.extend(node.orelse)
        else:
            pending.extend(child for child in ast.iter_child_nodes(node)
                           if isinstance(child, ast.stmt) or hasattr(child, "body"))


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or \
        (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imported_modules(module: Module, modules: dict) -> set:
    """The modules of ``modules`` that ``module`` imports as it loads (module doc)."""
    found = set()
    for node in load_time_imports(module.tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
            continue
        if node.level:
            base = module.package.split(".")
            base = base[:len(base) - node.level + 1]
            target = ".".join(base + ([node.module] if node.module else []))
        else:
            target = node.module or ""
        for alias in node.names:
            submodule = f"{target}.{alias.name}"
            found.add(submodule if submodule in modules else target)
    return {name for name in found if name in modules and name != module.name}


def module_graph(modules: dict) -> dict:
    return {name: imported_modules(module, modules) for name, module in modules.items()}


def package_node(module: Module, depth: int) -> str:
    """The node standing for ``module`` in the package graph at ``depth`` (module doc): its
    package cut to ``depth`` levels below the top one, or the module itself when it lies
    directly in the top folder."""
    parts = module.package.split(".")
    if len(parts) == 1 and module.name != module.package:
        return module.name
    return ".".join(parts[:depth + 1])


def package_graph(modules: dict, graph: dict, depth: int) -> dict:
    packages = defaultdict(set)
    for name, imported in graph.items():
        here = package_node(modules[name], depth)
        packages[here].update(there for other in imported
                              if (there := package_node(modules[other], depth)) != here)
    return dict(packages)


def cycles(graph: dict) -> list:
    """A shortest cycle through each strongly connected component of more than one node."""
    return [cycle_path(graph, component) for component in components(graph)]


def components(graph: dict) -> list:
    """The strongly connected components of more than one node, as sets (Tarjan's algorithm,
    without recursion)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, edges = work[-1]
            step = next(edges, None)
            if step is not None:
                if step not in index:
                    index[step] = low[step] = len(index)
                    stack.append(step)
                    on_stack.add(step)
                    work.append((step, iter(sorted(graph.get(step, ())))))
                elif step in on_stack:
                    low[node] = min(low[node], index[step])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.add(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(component)
    return found


def cycle_path(graph: dict, component: set) -> list:
    """A shortest cycle through the component's first node (by name), first node repeated at
    the end: a -> b -> a."""
    start = min(component)
    previous, frontier = {start: None}, [start]
    while frontier:
        following = []
        for node in frontier:
            for step in sorted(graph.get(node, ())):
                if step == start:
                    path = [node]
                    while previous[path[-1]] is not None:
                        path.append(previous[path[-1]])
                    return path[::-1] + [start]
                if step in component and step not in previous:
                    previous[step] = node
                    following.append(step)
        frontier = following
    return sorted(component)


def package_components(modules: dict, graph: dict) -> list:
    """(depth, package graph, component) for every package cycle at every depth."""
    deepest = max(len(module.package.split(".")) for module in modules.values()) - 1
    return [(depth, packages, component) for depth in range(1, deepest + 1)
            for packages in [package_graph(modules, graph, depth)]
            for component in components(packages)]


def package_cycles(modules: dict, graph: dict) -> list:
    """(depth, a shortest cycle) for every package cycle at every depth."""
    return [(depth, cycle_path(packages, component))
            for depth, packages, component in package_components(modules, graph)]


def print_cycle(prefix: str, graph: dict, component: set) -> None:
    """The cycle, and the other nodes of its component (which take part in other cycles)."""
    path = cycle_path(graph, component)
    others = sorted(component - set(path))
    print(f"  {prefix}" + " -> ".join(path) + (f"  (with {', '.join(others)})" if others else ""))


class Function(NamedTuple):
    module: str
    name: str
    line: int
    parameters: int
    lines: int


def functions(modules: dict) -> list:
    """Every function and method, with its parameter count (self and cls included, * and **
    as one each) and its length in lines (decorators and docstring included)."""
    found = []
    for module in modules.values():
        for node in ast.walk(module.tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                a = node.args
                count = (len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                         + (a.vararg is not None) + (a.kwarg is not None))
                first = min([node.lineno] + [d.lineno for d in node.decorator_list])
                found.append(Function(module.name, node.name, node.lineno, count,
                                      node.end_lineno - first + 1))
    return found


def report(source: Path = SOURCE) -> int:
    """Print the measures; the number of import cycles found."""
    modules = read_modules(source)
    found = functions(modules)
    many = sorted((f for f in found if f.parameters > MAX_PARAMETERS),
                  key=lambda f: -f.parameters)
    print(f"functions over {MAX_PARAMETERS} parameters: {len(many)}")
    for f in many:
        print(f"  {f.parameters:4d}  {f.module}.{f.name} (line {f.line})")
    long = sorted((f for f in found if f.lines > MAX_FUNCTION_LINES), key=lambda f: -f.lines)
    print(f"functions over {MAX_FUNCTION_LINES} lines: {len(long)}")
    for f in long:
        print(f"  {f.lines:4d}  {f.module}.{f.name} (line {f.line})")
    sizes = sorted(((len(m.path.read_text().splitlines()), m.name) for m in modules.values()),
                   reverse=True)
    big = [(lines, name) for lines, name in sizes if lines > MAX_MODULE_LINES]
    print(f"modules over {MAX_MODULE_LINES} lines: {len(big)}")
    for lines, name in big:
        print(f"  {lines:4d}  {name}")
    graph = module_graph(modules)
    module_cycles = components(graph)
    print(f"import cycles between modules: {len(module_cycles)}")
    for component in module_cycles:
        print_cycle("", graph, component)
    between_packages = package_components(modules, graph)
    print(f"import cycles between packages: {len(between_packages)}")
    for depth, packages, component in between_packages:
        print_cycle(f"depth {depth}: ", packages, component)
    return len(module_cycles) + len(between_packages)


if __name__ == "__main__":
    report(Path(sys.argv[1]) if len(sys.argv) > 1 else SOURCE)
