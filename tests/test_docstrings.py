"""Every public name documents itself as the field expects (numpydoc): its parameters,
what it returns (or its attributes), the errors it raises, and an example that runs."""

from __future__ import annotations

import doctest
import importlib
import inspect
import pkgutil

import pytest
from doctest_namespace import shared

import superfacets

#: Sections a public function must have; a class has Attributes (or Parameters) instead
#: of Returns. Constants (DEFAULTS) and errors (one-line exception classes) are exempt
#: from all but a docstring.
FUNCTION = ("Parameters", "Returns", "Raises", "Examples")
CLASS = ("Examples",)
ERRORS = {"SuperfacetsError", "ParameterError", "InvalidMeshError", "InvalidCloudError",
          "MeshFormatError", "MemoryLimitError", "MissingExtraError"}


def _sections(doc: str) -> set[str]:
    lines = inspect.cleandoc(doc).splitlines()
    return {a.strip() for a, b in zip(lines, lines[1:]) if b.strip() and set(b.strip()) == {"-"}}


@pytest.mark.parametrize("name", sorted(superfacets.__all__))
def test_every_public_name_has_the_sections(name):
    obj = getattr(superfacets, name)
    doc = inspect.getdoc(obj)
    assert doc, f"{name} has no docstring"
    if name in ERRORS or name == "DEFAULTS":
        return
    have = _sections(doc)
    if inspect.isclass(obj):
        want = set(CLASS) | ({"Attributes"} if "Parameters" not in have else {"Parameters"})
    else:
        want = set(FUNCTION)
    missing = sorted(want - have)
    assert not missing, f"{name}: no {', '.join(missing)} section"


#: Every module of the package: the examples of private modules run too (a broken one
#: misleads whoever reads the code as much as a user).
MODULES = sorted(m.name for m in pkgutil.walk_packages(superfacets.__path__, "superfacets.")
                 if m.name != "superfacets.__main__"
                 and not m.name.startswith("superfacets._kernels._cxx"))


@pytest.mark.parametrize("module", MODULES)
def test_the_examples_run(module, tmp_path, monkeypatch):
    """The Examples of the public modules run as doctests (in a scratch folder), in the
    shared namespace (:mod:`doctest_namespace`: ``np``, ``trimesh``, ``segment``, ...)."""
    monkeypatch.chdir(tmp_path)
    mod = importlib.import_module(module)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = _Runner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    globs = {**shared(), **vars(mod)}  # (the shared names, the module's own first)
    for test in finder.find(mod, module, globs=globs):
        runner.run(test)
    result = runner.summarize(verbose=False)
    if result.failed and result.failed == len(runner.missing):  # an extra not installed
        pytest.skip(f"{module}: its examples need {', '.join(sorted(set(runner.missing)))}")
    assert result.failed == 0, f"{result.failed} example(s) of {module} failed"


class _Runner(doctest.DocTestRunner):
    """A doctest runner that tells an example stopped by a missing optional extra (the
    package's own one-line refusal, which names it) from one that failed."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.missing: list[str] = []

    def report_unexpected_exception(self, out, test, example, exc_info):
        from superfacets.errors import MissingExtraError

        if isinstance(exc_info[1], MissingExtraError):
            self.missing.append(str(exc_info[1]).split(" needs ")[-1].split(",")[0])
            return
        super().report_unexpected_exception(out, test, example, exc_info)


#: The modules of the API reference (docs/api.rst) and those a user reaches from the
#: guide and the gallery (files, pictures, pages, batches, tiles, inputs): every public
#: function and class of theirs documents itself as the package's root names do.
REFERENCE = ("superfacets.method.params", "superfacets.method.rules", "superfacets.checks",
             "superfacets.elements.kinds", "superfacets.elements.builders",
             "superfacets.elements.features", "superfacets.method.stages",
             "superfacets.method.finish", "superfacets.method.pipeline",
             "superfacets.evaluation.metrics", "superfacets.evaluation.contingency",
             "superfacets.graph.hierarchy", "superfacets.graph.adjacency",
             "superfacets.api.levels", "superfacets.api.scenes", "superfacets.api.result",
             "superfacets.io.clouds", "superfacets.io.headers", "superfacets.io.labels",
             "superfacets.io.tetmeshes", "superfacets.viz.html", "superfacets.scale.tiles.run",
             "superfacets.inputs.tetmesh", "superfacets.inputs.convert",
             "superfacets.graph.learning", "superfacets.api.sizes", "superfacets.io.records",
             "superfacets.io.orientation")


def _reference_names():
    for module in REFERENCE:
        mod = importlib.import_module(module)
        for name in getattr(mod, "__all__", ()):
            obj = getattr(mod, name, None)
            if getattr(obj, "__module__", None) == module and (
                    inspect.isfunction(obj) or (inspect.isclass(obj)
                                                and not issubclass(obj, Exception))):
                yield f"{module}.{name}", obj


_REFERENCE_NAMES = list(_reference_names())


# (ids from the names alone: an object's repr holds its address, which differs between
# the processes of a parallel run)
@pytest.mark.parametrize("name, obj", _REFERENCE_NAMES, ids=[n for n, _ in _REFERENCE_NAMES])
def test_every_name_of_the_reference_modules_has_the_sections(name, obj):
    have = _sections(inspect.getdoc(obj) or "")
    want = set(CLASS) if inspect.isclass(obj) else set(FUNCTION)
    if inspect.isfunction(obj) and not inspect.signature(obj).parameters:
        want.discard("Parameters")
    missing = sorted(want - have)
    assert not missing, f"{name}: no {', '.join(missing)} section"


@pytest.mark.parametrize("module", REFERENCE)
def test_the_reference_modules_examples_run(module, tmp_path, monkeypatch):
    test_the_examples_run(module, tmp_path, monkeypatch)
