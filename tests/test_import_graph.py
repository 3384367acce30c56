"""The plan of the house, measured: every fe_beam module's imports (module level, inside
functions, and ``importlib`` strings naming fe_beam modules) form no cycle; no module imports
another fe_beam module inside a function; no import climbs a layer of the import-linter
contract in pyproject.toml; and `lint-imports` fails on an injected upward import.

Run with ``-s`` to see the counts (modules, edges, cycles, function-local imports, upward
imports) that the issue asks to report."""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "fe_beam"


def modules(root: Path = ROOT) -> dict[str, Path]:
    found = {}
    for path in sorted((root / "fe_beam").rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    if not node.level:
        return node.module or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def import_graph(root: Path = ROOT):
    """{module: {imported fe_beam module: 'module' | 'function' | 'string'}}."""
    known = modules(root)

    def nearest(name: str) -> str | None:
        while name and name not in known:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for name, path in known.items():
        tree = ast.parse(path.read_text())
        in_function = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                in_function.update(id(n) for n in ast.walk(node) if n is not node)
        edges = {}
        for node in ast.walk(tree):
            kind = "function" if id(node) in in_function else "module"
            targets = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = _resolve(name, path.name == "__init__.py", node)
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base
                           for a in node.names]
            elif (isinstance(node, ast.Constant) and isinstance(node.value, str)
                  and node.value.startswith("fe_beam.") and " " not in node.value):
                # an importlib string (a lazy table, importlib.import_module("fe_beam.x"))
                text = node.value.split(":")[0]
                target = text if text in known else text.rpartition(".")[0]
                targets, kind = ([target] if target in known else []), "string"
            for target in targets:
                if not target.startswith("fe_beam"):
                    continue
                target = nearest(target)
                if target and target != name and not (kind == "string" and target == "fe_beam"):
                    if edges.get(target) != "function":
                        edges[target] = kind
        graph[name] = edges
    return graph


def cycles(graph) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    counter = [0]
    sys.setrecursionlimit(max(10_000, sys.getrecursionlimit()))

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
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
                found.append(sorted(component))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def layers() -> list[list[str]]:
    """The layers of the import-linter contract (top first), each a list of module names."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    contract = next(c for c in config["tool"]["importlinter"]["contracts"]
                    if c["type"] == "layers")
    return [[name.strip().strip("()") for name in layer.replace("|", ":").split(":")]
            for layer in contract["layers"]]


def layer_of(module: str, order) -> int | None:
    for rank, names in enumerate(order):
        if any(module == name or module.startswith(name + ".") for name in names):
            return rank
    return None


def upward_imports(graph) -> list[str]:
    order = layers()
    found = []
    for source, edges in graph.items():
        for target in edges:
            a, b = layer_of(source, order), layer_of(target, order)
            if a is not None and b is not None and b < a:
                found.append(f"{source} -> {target}")
    return sorted(found)


def test_the_package_has_no_import_cycle_and_no_function_local_import():
    graph = import_graph()
    found = cycles(graph)
    local = sorted(f"{m} -> {t}" for m, edges in graph.items() for t, kind in edges.items()
                   if kind == "function")
    upward = upward_imports(graph)
    print(f"\nimport graph: {len(graph)} modules, {sum(map(len, graph.values()))} edges, "
          f"{sum(len(c) for c in found)} modules in cycles, {len(local)} function-local "
          f"imports, {len(upward)} upward imports")
    assert not found, f"import cycles: {found}"
    assert not local, "function-local imports between fe_beam modules:\n" + "\n".join(local)
    assert not upward, "imports that climb a layer:\n" + "\n".join(upward)


def test_the_checker_sees_cycles_local_imports_and_strings(tmp_path):
    """The walk would catch each kind of import it claims to (a checker that sees nothing
    passes any code)."""
    copy = tmp_path / "fe_beam"
    copy.mkdir()
    (copy / "__init__.py").write_text("")
    (copy / "a.py").write_text("def f():\n    from fe_beam import b\n")
    (copy / "b.py").write_text("import importlib\nNAMES = {'x': 'fe_beam.c'}\n")
    (copy / "c.py").write_text("import fe_beam.a\n")
    graph = import_graph(tmp_path)
    assert graph["fe_beam.a"] == {"fe_beam.b": "function"}
    assert graph["fe_beam.b"] == {"fe_beam.c": "string"}
    assert cycles(graph) == [["fe_beam.a", "fe_beam.b", "fe_beam.c"]]


def _lint_imports() -> str | None:
    found = shutil.which("lint-imports") or str(Path(sys.executable).parent / "lint-imports")
    return found if Path(found).exists() else None


@pytest.mark.skipif(_lint_imports() is None, reason="import-linter is not installed")
def test_lint_imports_passes_and_fails_on_an_injected_upward_import(tmp_path):
    scratch = tmp_path / "repo"
    shutil.copytree(PACKAGE, scratch / "fe_beam",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", scratch / "pyproject.toml")

    def lint() -> subprocess.CompletedProcess:
        return subprocess.run([_lint_imports(), "--no-cache"], cwd=scratch, text=True,
                              capture_output=True, env={"PYTHONPATH": str(scratch),
                                                        "PATH": "/usr/bin:/bin"},
                              timeout=300)

    clean = lint()
    assert clean.returncode == 0, clean.stdout + clean.stderr
    mpi = scratch / "fe_beam" / "fem" / "mpi.py"
    mpi.write_text(mpi.read_text() + "\nfrom fe_beam.analyses import static  # noqa\n")
    broken = lint()
    assert broken.returncode != 0
    assert "fe_beam.fem.mpi -> fe_beam.analyses" in broken.stdout
