"""The package's shape (README "Layout"): modules in layers, imports only downwards,
no import circle, no module over the size a reader can hold.

Every ``import`` in ``src/superfacets`` counts, also those inside functions
(lazy imports still tie modules together) and under ``TYPE_CHECKING``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "superfacets"

#: Layers, lowest first, one line a floor of folders (README "Layout"): a module may
#: import modules of its own folder or of a lower floor, never of a higher one, nor of
#: another folder of its own floor. A module's layer is that of the longest prefix listed.
LAYERS = (
    ("superfacets._version", "superfacets.errors"),  # what every module may raise
    ("superfacets._kernels",),  # the compiled kernels
    ("superfacets.checks",),  # one rule for each kind of argument
    ("superfacets._runtime",),  # threads, memory, signals, optional extras
    ("superfacets.inputs",),  # validated meshes, clouds and tetrahedral meshes
    ("superfacets.elements",),  # their element graphs, the kinds, labels, density
    ("superfacets.io",),  # files: reading, writing, labels, colours
    ("superfacets.graph",),  # the superfacet graph and the hierarchy
    ("superfacets.method",),  # the method: parameters, stages, one run
    ("superfacets.api",),  # the public functions and their results
    ("superfacets.viz", "superfacets.evaluation"),  # pictures; measures, baselines, reports
    ("superfacets.scale", "superfacets.scale.runner"),  # the engine, batches, experiments
    ("superfacets.scale.tiles",),  # the tiled run (on the engine)
    ("superfacets.cli",),  # the command line
    ("superfacets.__main__",),  # python -m superfacets
    ("superfacets",),  # the public facade (imports everything lazily; nothing imports it)
)

#: At most this many entries at the package's top (besides __init__, __main__, _version
#: and py.typed): sub-packages by concept, a reader finds a room by its name.
MAX_TOP = 16

#: The most lines of code a function may have (its docstring apart): one a reader holds
MAX_FUNCTION_LINES = 80


def _modules() -> dict[str, Path]:
    out = {}
    for p in SRC.rglob("*.py"):
        parts = list(p.relative_to(SRC.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


MODULES = _modules()


def _imports(name: str, path: Path) -> set[str]:
    """The package's modules imported by one module (any depth in its code)."""
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            stem = ".".join(base + ([node.module] if node.module else []))
            targets = [f"{stem}.{a.name}" if f"{stem}.{a.name}" in MODULES else stem
                       for a in node.names]
        else:
            continue
        for t in targets:
            while t and t not in MODULES:
                t = t.rpartition(".")[0]
            if t and t != name:
                found.add(t)
    return found


GRAPH = {name: _imports(name, path) for name, path in MODULES.items()}


def layer_of(name: str) -> int:
    best, layer = -1, None
    for i, prefixes in enumerate(LAYERS):
        for prefix in prefixes:
            if (name == prefix or name.startswith(prefix + ".")) and len(prefix) > best:
                best, layer = len(prefix), i
    if layer is None:
        raise AssertionError(f"{name} is in no layer: add it to LAYERS in {__file__}")
    return layer


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_every_module_has_a_layer():
    for name in MODULES:
        layer_of(name)


def _folder(name: str) -> str:
    """The sub-package (or top module) a module belongs to: its folder."""
    return ".".join(name.split(".")[:2])


def test_no_import_runs_up_the_layers():
    upward = sorted(f"{a} (layer {layer_of(a)}) imports {b} (layer {layer_of(b)})"
                    for a, targets in GRAPH.items() for b in targets
                    if layer_of(b) > layer_of(a))
    assert upward == [], "\n".join(upward)


def test_no_two_folders_import_each_other():
    """Folders are floors: between two folders imports run one way (on one floor, none)."""
    edges = {(_folder(a), _folder(b)) for a, targets in GRAPH.items() for b in targets
             if _folder(a) != _folder(b)}
    both = sorted(f"{a} <-> {b}" for a, b in edges if (b, a) in edges and a < b)
    same = sorted(f"{a} -> {b}" for a, b in edges
                  if layer_of(a) == layer_of(b) and a != "superfacets")
    assert both == [] and same == [], both + same


def test_no_import_circle():
    assert _cycles(GRAPH) == []


def _code_lines(node) -> int:
    """Lines of a function's code: from the first statement after its docstring."""
    body = node.body
    first = body[0]
    if (isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant)
            and isinstance(first.value.value, str) and len(body) > 1):
        first = body[1]
    return node.end_lineno - first.lineno + 1


def test_no_function_is_too_long():
    long = sorted(f"{name}:{node.lineno} {node.name}: {n} lines"
                  for name, path in MODULES.items()
                  for node in ast.walk(ast.parse(path.read_text()))
                  if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
                  and (n := _code_lines(node)) > MAX_FUNCTION_LINES)
    assert long == [], f"split these (at most {MAX_FUNCTION_LINES} lines of code): {long}"


@pytest.mark.parametrize("case", [
    ({"a": {"b"}, "b": {"a"}}, [["a", "b"]]),
    ({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}, [["a", "b", "c"]]),
    ({"a": {"b"}, "b": {"c"}, "c": set()}, []),
])
def test_the_circle_finder_finds_circles(case):
    graph, expected = case
    assert _cycles(graph) == expected


def test_the_import_reader_sees_lazy_and_relative_imports(tmp_path):
    path = tmp_path / "x.py"
    path.write_text("from .inputs.mesh import Mesh\nfrom .io.files import Outputs\n"
                    "def f():\n    from .elements.faces import face_graph\n"
                    "    import superfacets.io\n")
    assert _imports("superfacets.x", path) == {"superfacets.inputs.mesh", "superfacets.io.files",
                                                "superfacets.elements.faces", "superfacets.io"}
    path.write_text("from ..errors import ParameterError\nfrom . import options\n")
    assert _imports("superfacets.cli.x", path) == {"superfacets.errors",
                                                    "superfacets.cli.options"}


def test_the_top_holds_few_entries():
    entries = sorted(p.name for p in SRC.iterdir() if p.name not in (
        "__init__.py", "__main__.py", "_version.py", "py.typed", "__pycache__"))
    assert len(entries) <= MAX_TOP, f"{len(entries)} entries at the top: {entries}"


def test_no_private_name_crosses_a_module():
    """``from .x import _name`` between modules: a private name is its module's own."""
    found = []
    for name, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith(
                    "superfacets")):
                for a in node.names:
                    if a.name.startswith("_") and not a.name.startswith("__"):
                        found.append(f"{name}: {a.name} from {node.module}")
    assert not found, "\n".join(found)


def test_old_module_paths_are_gone():
    """The import paths from before the sub-packages (never released) are not kept."""
    import importlib

    for old in ("superfacets.metrics", "superfacets.runner", "superfacets.params"):
        with pytest.raises(ModuleNotFoundError):
            importlib.import_module(old)


#: What the repository's root holds (tracked): anything else is a file a run or a doctest
#: left there and a commit picked up.
ROOT = {".ci", ".gitignore", "CHANGELOG.md", "CMakeLists.txt", "LICENSE", "Makefile",
        "README.md", "benchmarks", "docs", "pyproject.toml", "src", "tests", "tools"}


def test_the_repository_root_holds_only_the_project_s_own_entries():
    import shutil
    import subprocess

    root = Path(__file__).resolve().parent.parent
    if shutil.which("git") is None or not (root / ".git").exists():
        pytest.skip(f"{root}: not a git checkout")
    tracked = subprocess.run(["git", "ls-files"], cwd=root, capture_output=True, text=True,
                             check=True).stdout.split()
    stray = sorted({p.split("/")[0] for p in tracked} - ROOT)
    assert not stray, f"tracked at the repository's root: {stray}"
