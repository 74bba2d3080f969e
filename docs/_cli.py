"""The command-line pages, written from the parser at every build (they cannot drift)."""

from __future__ import annotations

import os
from pathlib import Path

HEAD = """The command line
================

``superfacets COMMAND --help`` prints what these pages show; they are written from the
same parser each time the documentation is built. Every command that segments takes the
method's options (``-k``, ``--alpha``, ``--paper``, ...), declared once with the Python
API's parameters (``superfacets.method.params.PARAMETERS``).

.. toctree::
   :maxdepth: 1

{toc}

.. code-block:: text

{main}
"""


def write_cli_pages(folder: Path) -> None:
    """Write ``folder/index.rst`` (the main help) and one page per command."""
    os.environ["COLUMNS"] = "92"  # argparse wraps to this width
    from superfacets.cli import build_parser

    folder.mkdir(parents=True, exist_ok=True)
    parser = build_parser()
    sub = parser._subparsers._group_actions[0]
    helps = {a.dest: a.help for a in sub._choices_actions}
    _write(folder / "index.rst", HEAD.format(
        toc="\n".join(f"   {name}" for name in sub.choices), main=_indent(parser.format_help())))
    for name, p in sub.choices.items():
        title = f"superfacets {name}"
        _write(folder / f"{name}.rst", "\n".join(
            [title, "=" * len(title), "", (helps.get(name) or "").capitalize() + ".", "",
             ".. code-block:: text", "", _indent(p.format_help())]))


def _write(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def _indent(text: str) -> str:
    return "\n".join(("   " + line) if line.strip() else "" for line in text.splitlines()) + "\n"


def write_parameter_table(path: Path) -> None:
    """A Markdown table of ``superfacets.method.params.PARAMETERS`` (the one declaration)."""
    from superfacets.method.params import PARAMETERS

    rows = ["| parameter | default | option | applies to | what it is |", "|---|---|---|---|---|"]
    for p in PARAMETERS:
        kinds = "all" if len(p.kinds) == 4 else ", ".join(p.kinds)
        default = "auto" if p.default is None else f"`{p.default!r}`"
        rows.append(f"| `{p.name}` | {default} | `{p.cli or ''}` | {kinds} | {p.doc} |")
    _write(path, "\n".join(rows) + "\n")
