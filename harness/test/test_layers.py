"""The harness's modules in layers: no import cycle (function-local imports included), and none
longer than 400 lines."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "harness"
MAX_LINES = 400


def harness_imports(path: Path, modules: set[str]) -> set[str]:
    """The harness modules `path` imports anywhere in it."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            if node.module == "harness":
                found.update(alias.name for alias in node.names)
            elif node.module.startswith("harness."):
                found.add(node.module.split(".")[1])
        elif isinstance(node, ast.Import):
            found.update(a.name.split(".")[1] for a in node.names if a.name.startswith("harness."))
    return found & modules


def test_the_harness_has_no_import_cycle():
    paths = {p.stem: p for p in PACKAGE.glob("*.py")}
    graph = {name: harness_imports(path, set(paths)) for name, path in paths.items()}
    visiting, done, cycles = [], set(), []

    def visit(name):
        visiting.append(name)
        for dep in sorted(graph[name]):
            if dep in visiting:
                cycles.append(visiting[visiting.index(dep) :] + [dep])
            elif dep not in done:
                visit(dep)
        visiting.pop()
        done.add(name)

    for name in sorted(graph):
        if name not in done:
            visit(name)
    assert not cycles, " ; ".join(" -> ".join(c) for c in cycles)


def test_no_module_is_longer_than_400_lines():
    lengths = {p.stem: len(p.read_text().splitlines()) for p in PACKAGE.glob("*.py")}
    assert not {name: n for name, n in lengths.items() if n > MAX_LINES}
