"""Check a built documentation site: every local link and image resolves, and no page
loads a script or a stylesheet from the network (the site works offline).

Usage: python tools/check_site.py [docs/_build/html]

Prints each broken reference as ``page: target`` and exits 1 if there is any; the
``make docs`` target runs it after Sphinx.
"""

from __future__ import annotations

import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit


class _References(HTMLParser):
    """The ``href`` and ``src`` of a page's tags (``(tag, attribute, value)``)."""

    def __init__(self):
        super().__init__()
        self.found: list[tuple[str, str, str]] = []

    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name in ("href", "src") and value:
                self.found.append((tag, name, value))


def problems(site: Path) -> list[str]:
    """``page: target (why)`` of every broken local reference and network asset."""
    out = []
    for page in sorted(site.rglob("*.html")):
        if page.relative_to(site).parts[0] == "_static":  # (the theme's templates)
            continue
        refs = _References()
        refs.feed(page.read_text(encoding="utf-8", errors="replace"))
        for tag, _, value in refs.found:
            url = urlsplit(value)
            rel = page.relative_to(site)
            if url.scheme in ("http", "https") or value.startswith("//"):
                if tag in ("script", "img") or (tag == "link" and ".css" in url.path):
                    out.append(f"{rel}: {value} (loaded from the network)")
                continue
            if url.scheme or not url.path:  # mailto:, javascript:, #anchors
                continue
            target = (page.parent / unquote(url.path)).resolve()
            if not target.exists():
                out.append(f"{rel}: {value} (missing)")
    return out


def main(argv: list[str]) -> int:
    site = Path(argv[1] if len(argv) > 1 else "docs/_build/html")
    if not site.is_dir():
        print(f"{site}: no built site (make docs)", file=sys.stderr)
        return 1
    found = problems(site)
    for line in found:
        print(line)
    pages = sum(1 for _ in site.rglob("*.html"))
    print(f"{pages} pages, {len(found)} broken references", file=sys.stderr)
    return 1 if found else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
