"""The documentation's shape: pages a user can read (short, no lab-journal words), the
README within its length, and the generated pages made from the code they describe."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _pages():
    for p in sorted(DOCS.rglob("*")):
        if p.suffix in (".md", ".rst") and not {"_build", "auto_examples", "generated",
                                                 "results"} & set(p.parts):
            yield p


def test_user_pages_are_short_and_notes_hold_the_records():
    long = [f"{p.relative_to(DOCS)}: {len(p.read_text().splitlines())} lines" for p in _pages()
            if "notes" not in p.parts and len(p.read_text().splitlines()) > 400]
    assert not long, long
    assert len((ROOT / "README.md").read_text().splitlines()) <= 220


def test_no_page_speaks_of_issues_or_sessions():
    words = re.compile(r"\b(issue \d+|sessions?)\b", re.I)
    found = [f"{p.relative_to(ROOT)}: {m.group(0)}" for p in [*_pages(), ROOT / "README.md"]
             for m in words.finditer(p.read_text())]
    assert not found, found


def test_the_generated_pages_come_from_the_code(tmp_path):
    import sys

    sys.path.insert(0, str(DOCS))
    try:
        from _cli import write_cli_pages, write_parameter_table
    finally:
        sys.path.remove(str(DOCS))
    from superfacets.cli import build_parser
    from superfacets.method.params import PARAMETERS

    write_cli_pages(tmp_path / "cli")
    write_parameter_table(tmp_path / "table.md")
    commands = build_parser()._subparsers._group_actions[0].choices
    assert {p.stem for p in (tmp_path / "cli").glob("*.rst")} == set(commands) | {"index"}
    assert "--extent-weight" in (tmp_path / "cli" / "segment.rst").read_text()
    table = (tmp_path / "table.md").read_text()
    assert all(f"| `{p.name}` |" in table for p in PARAMETERS)


def test_every_gallery_example_ends_in_a_picture():
    examples = sorted((DOCS / "examples").glob("plot_*.py"))
    assert len(examples) >= 8
    for p in examples:
        text = p.read_text()
        assert "plt.show()" in text and text.lstrip().startswith('"""'), p.name


def test_the_changelog_has_a_short_entry_per_change():
    """One change, one entry of at most three lines: what was measured is in the docs."""
    import re

    text = (ROOT / "CHANGELOG.md").read_text()
    long = [e.splitlines()[0][:60] for e in re.split(r"\n(?=- |\n|#)", text)
            if e.startswith("- ") and len(e.splitlines()) > 3]
    assert not long, long
