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

#: Layers, lowest first: a module may import modules of its own layer or of a lower
#: one. A module's layer is that of the longest prefix listed here.
LAYERS = (
    # foundations: no knowledge of meshes
    ("superfacets._version", "superfacets.errors", "superfacets.checks", "superfacets.params",
     "superfacets.labels",
     "superfacets.elements.kinds",
     "superfacets.extras", "superfacets._threads", "superfacets._kernels",
     "superfacets.camera", "superfacets.warmup", "superfacets.interrupts", "superfacets.rgb"),
    # inputs: validated meshes and clouds, read from files or the libraries' objects
    ("superfacets.bounds", "superfacets.mesh", "superfacets.cloud", "superfacets.volume",
     "superfacets.convert", "superfacets.shapes", "superfacets.io.volumes",
     "superfacets.io.regions",
     "superfacets.io.files", "superfacets.io.ply", "superfacets.io.labels",
     "superfacets.io.meshes", "superfacets.io.clouds"),
    # element graphs of the inputs
    ("superfacets.elements",),
    # the method's pieces and the measures of a result
    ("superfacets.weights", "superfacets.expansion", "superfacets.classify",
     "superfacets.passes", "superfacets.initialization", "superfacets.multilevel",
     "superfacets.connectivity", "superfacets.cleanup", "superfacets.splitmerge",
     "superfacets.boundaries", "superfacets.metrics", "superfacets.colors",
     "superfacets.adjacency", "superfacets.adaptive",
     "superfacets.hierarchy"),
    # the method, one run
    ("superfacets.result", "superfacets.stages", "superfacets.pipeline", "superfacets.segmentation",
     "superfacets.scenes",
     "superfacets.tiling", "superfacets.tile_layout", "superfacets.levels"),
    # every method alike
    ("superfacets.baselines", "superfacets.methods"),
    # what is made of results: files, pictures, pages, experiments, batches
    ("superfacets.io", "superfacets.render", "superfacets.html", "superfacets.outputs",
     "superfacets.datasets", "superfacets.runner", "superfacets.report"),
    # the command line
    ("superfacets.cli", "superfacets.__main__"),
    # the public facade (imports everything lazily; nothing imports it)
    ("superfacets",),
)

MAX_LINES = 450


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


def test_no_import_runs_up_the_layers():
    upward = sorted(f"{a} (layer {layer_of(a)}) imports {b} (layer {layer_of(b)})"
                    for a, targets in GRAPH.items() for b in targets
                    if layer_of(b) > layer_of(a))
    assert upward == [], "\n".join(upward)


def test_no_import_circle():
    assert _cycles(GRAPH) == []


def test_no_module_is_too_long():
    long = sorted(f"{name}: {n} lines" for name, path in MODULES.items()
                  if (n := len(path.read_text().splitlines())) > MAX_LINES)
    assert long == [], f"split these by concept (at most {MAX_LINES} lines): {long}"


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
    path.write_text("from .mesh import Mesh\nfrom .io.files import Outputs\n"
                    "def f():\n    from .elements.faces import face_graph\n"
                    "    import superfacets.io\n")
    assert _imports("superfacets.x", path) == {"superfacets.mesh", "superfacets.io.files",
                                                "superfacets.elements.faces", "superfacets.io"}
    path.write_text("from ..errors import ParameterError\nfrom . import options\n")
    assert _imports("superfacets.cli.x", path) == {"superfacets.errors",
                                                    "superfacets.cli.options"}
