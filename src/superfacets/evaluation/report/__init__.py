"""Figures and tables from a results file of :func:`superfacets.scale.runner.run_experiment`.

- :func:`load_results`: the rows as a pandas DataFrame, the last row of each
  (mesh, method, parameters, ``n_segments``) kept, numbers parsed, and a
  ``series`` column naming the method and the parameters that vary;
- :func:`category_means` and :func:`summary`: per-category means, and their
  mean over categories (each category weighs the same, as in the paper);
- :func:`plot_curves`: the paper's Fig. 4 layout, metric against the number
  of superfacets, one curve per series, averaged over categories;
- :func:`plot_per_category`: the same for one metric, one panel per category;
- :func:`plot_cost`: the paper's Fig. 5 layout, seconds and peak memory
  against the number of faces (log scales); :func:`cost_table`;
- :func:`markdown_summary`: Markdown tables;
- :func:`write_report`: all of the above into a folder (PNG and SVG).

Tables are in :mod:`.tables`, figures in :mod:`.figures`.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Sequence

from ...checks import check_int
from ...io import atomic_write
from .figures import plot_cost, plot_curves, plot_per_category
from .tables import (
    METRIC_LABELS,
    category_means,
    cost_table,
    load_results,
    markdown_summary,
    ok_rows,
    summary,
)

__all__ = ["load_results", "category_means", "summary", "plot_curves", "plot_per_category",
           "plot_cost", "cost_table", "markdown_summary", "write_report", "METRIC_LABELS"]


def _save(fig, path: Path) -> Path:
    buf = io.BytesIO()
    fig.savefig(buf, format=path.suffix[1:], dpi=130, bbox_inches="tight")
    return atomic_write(path, buf.getvalue())


def write_report(results, out_dir, *, k_focus: int = 150, prefix: str = "",
                 series: Sequence[str] | None = None) -> list[Path]:
    """Write the figures (PNG and SVG) and ``summary.md`` of a results file.

    Parameters
    ----------
    results : path or sequence of paths
        Results CSV(s), pooled (see :func:`load_results`).
    out_dir : path
        Folder, created if needed.
    k_focus : int, default 150
        See :func:`markdown_summary`.
    prefix : str, optional
        Prepended to every file name.
    series : sequence of str, optional
        Only these series (see :func:`load_results`).

    Returns
    -------
    list of pathlib.Path
        ``fig4.{png,svg}`` (UE and compactness), ``fig4_extra.{png,svg}``
        (boundary recall and achievable accuracy), ``per_category_<metric>.{png,svg}``
        for UE and compactness, ``cost.{png,svg}`` (seconds and peak memory
        against faces, the Fig. 5 layout) and ``summary.md``.

    Raises
    ------
    ParameterError
        If the file has no successful row, a series is unknown, or ``k_focus`` is not a
        count (an integer >= 1).
    NotADirectoryError
        If ``out_dir`` or a folder above it is a file.
    """
    check_int("k_focus", k_focus, lo=1)  # (-3 drew every table of nothing)
    df = load_results(results, series=series)
    ok = ok_rows(df)  # (no successful row: refused before the folder is made)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():  # (the results file itself, given as -o)
        raise NotADirectoryError(f"{out}: exists and is not a folder (the report writes a "
                                 "folder of figures and tables)")
    above = next((p for p in out.parents if p.exists()), None)  # (the folders it makes)
    if above is not None and not above.is_dir():
        raise NotADirectoryError(f"{out}: {above} is a file, not a folder")
    out.mkdir(parents=True, exist_ok=True)
    written = []

    def has(*columns) -> bool:  # a row with a value in one of the columns
        return any(c in ok and bool(ok[c].notna().any()) for c in columns)

    plots = {  # each figure, and whether the rows hold anything it draws
        "fig4": (lambda: plot_curves(df), has("undersegmentation_error", "compactness")),
        "fig4_extra": (lambda: plot_curves(df, ("boundary_recall", "achievable_accuracy")),
                       has("boundary_recall", "achievable_accuracy")),
        "per_category_undersegmentation_error": (
            lambda: plot_per_category(df, "undersegmentation_error"),
            has("undersegmentation_error")),
        "per_category_compactness": (lambda: plot_per_category(df, "compactness"),
                                     has("compactness")),
        "cost": (lambda: plot_cost(df, k_focus), "n_faces" in ok and bool(
            ((ok["n_faces"].fillna(0) > 0) & (ok["seconds"].fillna(0) > 0)).any())),
    }
    left_out = []
    for name, (plot, drawable) in plots.items():
        if not drawable:  # (no ground truth, or no mesh)
            left_out.append(name)
            continue
        fig = plot()
        for ext in ("png", "svg"):
            written.append(_save(fig, out / f"{prefix}{name}.{ext}"))

    text = markdown_summary(df, k_focus=k_focus)
    if left_out:
        text += (f"\nNot drawn, the rows holding no value to draw (no ground truth, or no "
                 f"mesh): {', '.join(left_out)}.\n")
    written.append(atomic_write(out / f"{prefix}summary.md", text.encode()))
    return written
