"""Figures of experiment results, as matplotlib Figure objects.

Made without pyplot, so drawing them neither switches the backend of a
user's session nor leaves figures open.

- :func:`plot_curves`: the paper's Fig. 4 layout, metric against the number
  of superfacets, one curve per series, averaged over categories;
- :func:`plot_per_category`: the same for one metric, one panel per category;
- :func:`plot_cost`: the paper's Fig. 5 layout, seconds and peak memory
  against the number of faces (log scales).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ..._runtime.extras import require
from .tables import (
    METRIC_LABELS,
    category_means,
    mean_over,
    rows_at_k,
    segments_word,
    series_order,
    summary,
)

__all__ = ["plot_curves", "plot_per_category", "plot_cost"]


def _style(df):
    """Colour per series, line style and marker per method."""
    matplotlib = require("matplotlib", "making result figures")

    series = series_order(df)
    methods = list(dict.fromkeys(df["method"]))
    cmap = matplotlib.colormaps["tab10" if len(series) <= 10 else "tab20"]
    styles = ["-", "--", ":", "-."]
    markers = ["o", "s", "^", "D", "v", "P"]
    out = {}
    for i, s in enumerate(series):
        m = methods.index(df.loc[df["series"] == s, "method"].iloc[0])
        out[s] = dict(color=cmap(i % cmap.N), linestyle=styles[m % 4], marker=markers[m % 6])
    return out


def _subplots(nrows: int, ncols: int, figsize, squeeze: bool = False):
    """A figure and its axes, made without pyplot: no global state, no backend switch
    (a notebook's backend stays as it is)."""
    Figure = require("matplotlib.figure", "making result figures").Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, squeeze=squeeze)


def _figure_legend(fig, axes, most: int) -> int:
    """One legend below the figure for the series drawn on any of ``axes`` (each once, at
    most ``most`` a row); none where nothing was drawn. Returns how many it names."""
    handles, labels = [], []
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    if labels:
        fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), most),
                   frameon=False, fontsize=9)
    return len(labels)


def plot_curves(df, metrics: Sequence[str] = ("undersegmentation_error", "compactness"),
                title: str | None = None):
    """The paper's Fig. 4 layout: each metric against ``n_segments``, one curve per series.

    Values are means over categories of per-category means.

    Returns
    -------
    matplotlib.figure.Figure
    """
    style = _style(df)
    fig, axes = _subplots(1, len(metrics), figsize=(5.2 * len(metrics), 4.2), squeeze=False)
    for ax, metric in zip(axes[0], metrics):
        s = summary(df, metric)
        for name, row in s.iterrows():
            ax.plot(row.index, row.values, label=name, markersize=4, **style[name])
        if s.empty or not np.isfinite(s.to_numpy(dtype=float)).any():  # (no ground truth)
            ax.text(0.5, 0.5, "no values: the rows have no ground truth", ha="center",
                    va="center", transform=ax.transAxes, color="0.4")
        ax.set_xlabel(f"number of {segments_word(df)} asked (k)")
        ax.set_ylabel(METRIC_LABELS.get(metric, metric))
        ax.grid(True, alpha=0.3)
        ax.set_xticks(list(s.columns))
    n = _figure_legend(fig, axes.flat, 5)
    fig.suptitle(title or mean_over(df), fontsize=11)
    fig.tight_layout(rect=(0, 0.06 + 0.04 * ((max(n, 1) - 1) // 5), 1, 0.97))
    return fig


def plot_per_category(df, metric: str = "undersegmentation_error"):
    """One panel per category: ``metric`` against ``n_segments``, one curve per series.

    Returns
    -------
    matplotlib.figure.Figure
    """
    style = _style(df)
    cm = category_means(df, metric)
    cats = sorted(cm.index.get_level_values("category").unique())
    ncol = 5
    nrow = -(-len(cats) // ncol)
    fig, axes = _subplots(nrow, ncol, figsize=(3.2 * ncol, 2.5 * nrow + 0.8), squeeze=False)
    order = [s for s in series_order(df) if s in cm.index.get_level_values("series")]
    ks = sorted(cm.columns)
    for ax, cat in zip(axes.flat, cats):
        for s in order:
            if (s, cat) in cm.index:
                row = cm.loc[(s, cat)]
                ax.plot(row.index, row.values, label=s, markersize=3, **style[s])
        ax.set_title(cat, fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.set_xticks(ks)
        ax.tick_params(labelsize=7)
    for ax in axes.flat[len(cats):]:
        ax.axis("off")
    n = _figure_legend(fig, axes.flat, 5)
    fig.supxlabel(f"number of {segments_word(df)} asked (k)", fontsize=10, y=0.04)
    fig.supylabel(METRIC_LABELS.get(metric, metric), fontsize=10)
    fig.tight_layout(rect=(0, 0.06 + 0.03 * ((max(n, 1) - 1) // 5), 1, 1))
    return fig


def plot_cost(df, k_focus: int = 150):
    """The paper's Fig. 5 layout: seconds (and peak memory) against faces, log scales.

    One point per mesh and series at the ``n_segments`` nearest ``k_focus``;
    ``seconds`` is the method's time for one segmentation from scratch (work
    shared between values of ``k`` included). The memory panel is drawn when
    the rows have ``peak_mib`` (resident memory above the start of the call),
    with the ``4 m^2`` bytes of a dense float32 distance matrix for reference.

    Returns
    -------
    matplotlib.figure.Figure
    """
    k, at = rows_at_k(df, k_focus)
    style = _style(df)
    has_mem = "peak_mib" in at and at["peak_mib"].notna().any()
    panels = [("seconds", "seconds per segmentation (log)")]
    if has_mem:
        panels.append(("peak_mib", "peak memory above start, MiB (log)"))
    fig, axes = _subplots(1, len(panels), figsize=(5.4 * len(panels), 4.3), squeeze=False)
    order = [s for s in series_order(df) if s in set(at["series"])]
    for ax, (col, label) in zip(axes[0], panels):
        for name in order:
            sub = at[(at["series"] == name) & at[col].notna() & (at[col] > 0)]
            st = style[name]
            ax.scatter(sub["n_faces"], sub[col], s=14, color=st["color"], marker=st["marker"],
                       label=name, alpha=0.85)
        if col == "peak_mib":
            faces = np.geomspace(max(1, at["n_faces"].min()), at["n_faces"].max(), 50)
            ax.plot(faces, 4 * faces**2 / 2**20, color="0.5", linestyle=":", linewidth=1,
                    label="4 m² bytes (float32 distance matrix)")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("faces (log)")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.25)
    n = _figure_legend(fig, axes[0], 4)
    fig.suptitle(f"running time and memory against mesh size, k = {k}", fontsize=11)
    fig.tight_layout(rect=(0, 0.07 + 0.04 * ((max(n, 1) - 1) // 4), 1, 0.97))
    return fig
