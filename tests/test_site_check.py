"""The check of the built documentation site (tools/check_site.py, run by ``make docs``)."""

from __future__ import annotations

import importlib.util
from pathlib import Path


def _check_site():
    path = Path(__file__).resolve().parents[1] / "tools" / "check_site.py"
    spec = importlib.util.spec_from_file_location("check_site", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_broken_images_links_and_network_scripts_are_named(tmp_path):
    (tmp_path / "images").mkdir()
    (tmp_path / "images" / "a.png").write_bytes(b"png")
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "page.html").write_text(
        '<img src="../images/a.png"> <img src="images/a.png"> <a href="../index.html#x">i</a>'
        '<a href="https://example.org/">out</a> <a href="#top">top</a>'
        '<script src="https://cdn.example.org/x.js"></script>')
    (tmp_path / "index.html").write_text('<a href="notes/page.html">n</a>')
    (tmp_path / "_static").mkdir()
    (tmp_path / "_static" / "macros.html").write_text('<script src="{{ nowhere }}"></script>')
    found = _check_site().problems(tmp_path)
    assert found == ["notes/page.html: images/a.png (missing)",
                     "notes/page.html: https://cdn.example.org/x.js (loaded from the network)"]
    assert _check_site().main(["check_site", str(tmp_path)]) == 1
