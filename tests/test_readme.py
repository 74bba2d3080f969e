"""The README's Python blocks run, in order, as a newcomer would run them after
``make demo`` (issue 34: snippets that run in order)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def python_blocks(text: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_the_readme_has_python_blocks():
    assert len(python_blocks(README.read_text())) >= 5


def test_the_readme_python_runs_in_order(tmp_path, monkeypatch):
    pytest.importorskip("pyvista")  # to_pyvista
    from superfacets import write_mesh
    from superfacets.inputs.shapes import creature

    (tmp_path / "demo-output").mkdir()
    write_mesh(tmp_path / "demo-output" / "creature.off", creature(58))  # what make demo writes
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for i, block in enumerate(python_blocks(README.read_text())):
        try:
            exec(compile(block, f"README.md python block {i + 1}", "exec"), namespace)
        except Exception as exc:  # name the block: the README must change, not the test
            raise AssertionError(f"README python block {i + 1} fails: {exc!r}\n{block}") from exc
    assert (tmp_path / "demo-output" / "labels.seg").is_file()
    assert (tmp_path / "demo-output" / "scan.npy").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["demo-output"]  # nothing beside
    assert len(namespace["per_object"]) == 2 and namespace["scene_labels"].min() == 0
