"""One name per kernel across the language seam: ``kernel("source.name")`` is ``name``,
defined and bound in ``_kernels/cxx/source.cpp`` (the submodule ``_cxx.source``), its
reference in ``tests/oracle/source.py``; every binding shows its arguments' names and a
line of doc; no C++ source over 800 lines."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from superfacets._kernels import native

ROOT = Path(__file__).resolve().parents[2]
CXX = ROOT / "src" / "superfacets" / "_kernels" / "cxx"
ORACLE = ROOT / "tests" / "oracle"
SOURCES = sorted(p for p in CXX.glob("*.cpp") if p.name != "module.cpp")


def _addresses() -> set[str]:
    """Every ``kernel("source.name")`` of the package and its tests (a ``{...}`` name: an
    f-string's, checked for its source only)."""
    pattern = re.compile(r'kernel\(\s*f?"([a-z_]+\.[a-z_0-9{}]+)"')
    return {m for path in [*(ROOT / "src").rglob("*.py"), *(ROOT / "tests").rglob("*.py")]
            if path != Path(__file__).resolve() for m in pattern.findall(path.read_text())}


def _bound(source: Path) -> set[str]:
    return set(re.findall(r'm\.def\("(\w+)"', source.read_text()))


def test_every_address_names_the_source_that_binds_it():
    addresses = _addresses()
    assert len(addresses) > 70
    wrong = []
    for address in addresses:
        source, name = address.split(".")
        path = CXX / f"{source}.cpp"
        if not path.is_file() or ("{" not in name and name not in _bound(path)):
            wrong.append(address)
    assert not wrong, wrong


def test_every_source_has_its_oracle_and_stays_short():
    for path in SOURCES:
        text = path.read_text()
        head = "\n".join(text.splitlines()[:12])
        assert f"tests/oracle/{path.stem}.py" in head, f"{path.name}: no reference named"
        assert (ORACLE / f"{path.stem}.py").is_file(), path.name
        assert len(text.splitlines()) <= 800, f"{path.name}: {len(text.splitlines())} lines"
    stale = [p.name for p in CXX.iterdir() if re.search(r"superfacets/_kernels/\w+\.py",
                                                        p.read_text())]
    assert not stale, stale


@pytest.mark.skipif(not native.available(), reason="the compiled kernels are not built")
def test_each_binding_resolves_through_its_submodule_with_names_and_doc():
    cxx = native.require()
    count = 0
    for path in SOURCES:
        module = getattr(cxx, path.stem)
        for name in sorted(_bound(path)):
            fn = getattr(module, name)
            doc = fn.__doc__ or ""
            signature, _, text = doc.partition("\n")
            assert "arg0" not in signature and f"{name}(" in signature, signature
            assert text.strip(), f"{path.stem}.{name}: no doc"
            count += 1
        with pytest.raises(AttributeError, match="binds none of that name"):
            native.kernel(f"{path.stem}.no_such_kernel")
    assert count == 87
    with pytest.raises(AttributeError):  # a kernel of another source is not found here
        native.kernel("geometry.knn_csr")
