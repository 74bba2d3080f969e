"""Figures and tables from a results file of :func:`superfacets.experiment.run_experiment`.

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
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Sequence

import numpy as np

from .errors import ParameterError
from .metrics import METRICS

__all__ = ["load_results", "category_means", "summary", "plot_curves", "plot_per_category",
           "plot_cost", "cost_table", "markdown_summary", "write_report", "METRIC_LABELS"]

#: Axis labels of the metrics.
METRIC_LABELS = {
    "undersegmentation_error": "undersegmentation error (lower is better)",
    "compactness": "compactness (lower is better)",
    "boundary_recall": "boundary recall (higher is better)",
    "achievable_accuracy": "achievable segmentation accuracy (higher is better)",
    "seconds": "seconds per mesh",
}
_SHORT = {"undersegmentation_error": "UE", "compactness": "compactness",
          "boundary_recall": "boundary recall", "achievable_accuracy": "ASA"}
_GREEK = {"alpha": "α", "eta_convex": "η"}


def load_results(path, series: Sequence[str] | None = None):
    """Read a results file (or several) into a DataFrame.

    Parameters
    ----------
    path : path or sequence of paths
        CSV written by :func:`superfacets.experiment.run_experiment`; rows of
        several files are pooled (later files win on repeated keys).
    series : sequence of str, optional
        Keep only these series (names as in the ``series`` column, e.g.
        ``"superfacets α=200"``), in this order of appearance.

    Returns
    -------
    pandas.DataFrame
        One row per (mesh, method, parameters, ``n_segments``, ``seed``), the
        last one recorded when a row was retried; numeric columns parsed; a
        ``series`` column (method and the parameters that vary among that
        method's rows, e.g. ``"superfacets α=200"``).

    Raises
    ------
    FileNotFoundError
    superfacets.MeshFormatError
        If it is not a results file.
    ParameterError
        If a name in ``series`` matches no series (the message lists them).
    """
    import pandas as pd

    from .experiment import METHODS, read_results

    paths = [path] if isinstance(path, (str, Path)) else list(path)
    rows = [r for p in paths for r in read_results(p)]
    df = pd.DataFrame(rows)
    if df.empty:
        return df.assign(series=pd.Series(dtype=str))
    params = {m: sorted(METHODS[m].defaults) if m in METHODS else [] for m in df["method"].unique()}
    keycols = ["mesh", "method", "n_segments", "seed"]
    df["_key"] = df.apply(lambda r: tuple(r[c] for c in keycols)
                          + tuple(r.get(p, "") for p in params[r["method"]]), axis=1)
    df = df.drop_duplicates("_key", keep="last").drop(columns="_key").reset_index(drop=True)
    for c in ["mesh_id", "n_faces", "n_segments", "superfacets", "iterations", "seconds",
              "peak_mib", "n_ground_truths", *METRICS]:
        if c in df:
            df[c] = pd.to_numeric(df[c], errors="coerce")
    if "converged" in df:
        df["converged"] = df["converged"].map({"true": True, "false": False})
    df["series"] = _series(df, params)
    if series:
        known = set(df["series"])
        missing = [x for x in series if x not in known]
        if missing:
            raise ParameterError(f"no series {', '.join(map(repr, missing))}; present: "
                                 f"{', '.join(map(repr, _series_order(df)))}")
        df = df[df["series"].isin(series)].reset_index(drop=True)
    return df


def _series(df, params: dict):
    out = df["method"].copy()
    for m, names in params.items():
        sel = df["method"] == m
        varying = [p for p in names if p in df and df.loc[sel, p].nunique() > 1]
        if not varying:
            continue
        vals = df.loc[sel, varying].apply(
            lambda r: " ".join(f"{_GREEK.get(p, p)}={_num(r[p])}" for p in varying), axis=1)
        out[sel] = m + " " + vals
    return out


def _num(text: str) -> str:
    try:
        x = float(text)
    except (TypeError, ValueError):
        return str(text)
    return f"{x:g}"


def _series_order(df) -> list[str]:
    """Series sorted by method (first appearance), then numerically by parameter values."""
    order = []
    for m in dict.fromkeys(df["method"]):
        names = sorted(df.loc[df["method"] == m, "series"].unique(), key=_natural)
        order += names
    return order


def _natural(s: str):
    import re

    return [float(t) if re.fullmatch(r"-?\d+(\.\d+)?", t) else t
            for t in re.split(r"=| ", s)]


def _ok(df):
    if df.empty:
        raise ParameterError("the results file has no rows")
    ok = df[df["status"] == "ok"]
    if ok.empty:
        raise ParameterError("the results file has no successful row (status ok)")
    return ok


def category_means(df, metric: str):
    """Mean of a metric per (series, category, n_segments) over the successful rows.

    Returns
    -------
    pandas.DataFrame
        Index ``(series, category)``, one column per ``n_segments``.
    """
    ok = _ok(df)
    return ok.pivot_table(index=["series", "category"], columns="n_segments", values=metric,
                          aggfunc="mean")


def summary(df, metric: str):
    """Mean over categories of the per-category means (each category weighs the same).

    Returns
    -------
    pandas.DataFrame
        Index ``series`` (in :func:`load_results` order), one column per ``n_segments``.
    """
    cm = category_means(df, metric)
    s = cm.groupby(level="series").mean()
    return s.reindex([x for x in _series_order(df) if x in s.index])


def _style(df):
    """Colour per series, line style and marker per method."""
    import matplotlib

    series = _series_order(df)
    methods = list(dict.fromkeys(df["method"]))
    cmap = matplotlib.colormaps["tab10" if len(series) <= 10 else "tab20"]
    styles = ["-", "--", ":", "-."]
    markers = ["o", "s", "^", "D", "v", "P"]
    out = {}
    for i, s in enumerate(series):
        m = methods.index(df.loc[df["series"] == s, "method"].iloc[0])
        out[s] = dict(color=cmap(i % cmap.N), linestyle=styles[m % 4], marker=markers[m % 6])
    return out


def plot_curves(df, metrics: Sequence[str] = ("undersegmentation_error", "compactness"),
                title: str | None = None):
    """The paper's Fig. 4 layout: each metric against ``n_segments``, one curve per series.

    Values are means over categories of per-category means.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    style = _style(df)
    fig, axes = plt.subplots(1, len(metrics), figsize=(5.2 * len(metrics), 4.2), squeeze=False)
    for ax, metric in zip(axes[0], metrics):
        s = summary(df, metric)
        for name, row in s.iterrows():
            ax.plot(row.index, row.values, label=name, markersize=4, **style[name])
        ax.set_xlabel("number of superfacets asked (k)")
        ax.set_ylabel(METRIC_LABELS.get(metric, metric))
        ax.grid(True, alpha=0.3)
        ax.set_xticks(list(s.columns))
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 5), frameon=False,
               fontsize=9)
    n_cat = _ok(df)["category"].nunique()
    fig.suptitle(title or f"mean over {n_cat} categor{'y' if n_cat == 1 else 'ies'}",
                 fontsize=11)
    fig.tight_layout(rect=(0, 0.06 + 0.04 * ((len(labels) - 1) // 5), 1, 0.97))
    return fig


def plot_per_category(df, metric: str = "undersegmentation_error"):
    """One panel per category: ``metric`` against ``n_segments``, one curve per series.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    style = _style(df)
    cm = category_means(df, metric)
    cats = sorted(cm.index.get_level_values("category").unique())
    ncol = 5
    nrow = -(-len(cats) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.2 * ncol, 2.5 * nrow + 0.8), squeeze=False)
    order = [s for s in _series_order(df) if s in cm.index.get_level_values("series")]
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
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 5), frameon=False,
               fontsize=9)
    fig.supxlabel("number of superfacets asked (k)", fontsize=10, y=0.04)
    fig.supylabel(METRIC_LABELS.get(metric, metric), fontsize=10)
    fig.tight_layout(rect=(0, 0.06 + 0.03 * ((len(labels) - 1) // 5), 1, 1))
    return fig


def _at_k(df, k_focus: int):
    ok = _ok(df)
    ks = sorted(ok["n_segments"].unique())
    k = min(ks, key=lambda x: abs(x - k_focus))
    return k, ok[ok["n_segments"] == k]


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
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k, at = _at_k(df, k_focus)
    style = _style(df)
    has_mem = "peak_mib" in at and at["peak_mib"].notna().any()
    panels = [("seconds", "seconds per segmentation (log)")]
    if has_mem:
        panels.append(("peak_mib", "peak memory above start, MiB (log)"))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.4 * len(panels), 4.3), squeeze=False)
    order = [s for s in _series_order(df) if s in set(at["series"])]
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
    handles, labels = [], []
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 4), frameon=False,
               fontsize=9)
    fig.suptitle(f"running time and memory against mesh size, k = {k}", fontsize=11)
    fig.tight_layout(rect=(0, 0.07 + 0.04 * ((len(labels) - 1) // 4), 1, 0.97))
    return fig


def cost_table(df, k_focus: int = 150):
    """Per series at ``k_focus``: median and largest seconds and peak MiB, meshes.

    Returns
    -------
    pandas.DataFrame
    """
    import pandas as pd

    k, at = _at_k(df, k_focus)
    rows = {}
    for name in [s for s in _series_order(df) if s in set(at["series"])]:
        sub = at[at["series"] == name]
        r = {"meshes": sub["mesh"].nunique(), "faces (median)": sub["n_faces"].median(),
             "s (median)": sub["seconds"].median(), "s (max)": sub["seconds"].max()}
        if "peak_mib" in sub and sub["peak_mib"].notna().any():
            r["peak MiB (median)"] = sub["peak_mib"].median()
            r["peak MiB (max)"] = sub["peak_mib"].max()
        rows[name] = r
    return k, pd.DataFrame.from_dict(rows, orient="index")


def _cell(v, fmt: str) -> str:
    if isinstance(v, (float, np.floating)):
        return fmt.format(v) if np.isfinite(v) else ""
    return "" if v is None else str(v)


def _md_table(frame, fmt: str = "{:.3f}", index_name: str = "", formats=None) -> str:
    formats = formats or {}
    cols = [str(c) for c in frame.columns]
    lines = ["| " + " | ".join([index_name or frame.index.name or ""] + cols) + " |",
             "|" + "---|" * (len(cols) + 1)]
    for idx, row in frame.iterrows():
        cells = [_cell(v, formats.get(c, fmt)) for c, v in zip(cols, row.values)]
        lines.append("| " + " | ".join([str(idx)] + cells) + " |")
    return "\n".join(lines)


def markdown_summary(df, k_focus: int = 150) -> str:
    """Markdown tables of a results file.

    Parameters
    ----------
    df : pandas.DataFrame
        From :func:`load_results`.
    k_focus : int, default 150
        The ``n_segments`` of the per-category table (nearest one present).

    Returns
    -------
    str
        Undersegmentation error and compactness per series and ``n_segments``
        (means over categories); per series: every metric at ``k_focus``,
        iterations, converged fraction, seconds per mesh and row counts by
        status; per category at ``k_focus``: UE and compactness per series.
    """
    import pandas as pd

    ok = _ok(df)
    out = [f"Results: {ok['mesh'].nunique()} meshes, {ok['category'].nunique()} categories, "
           f"{len(df)} rows ({len(ok)} ok, {(df['status'] == 'failed').sum()} failed, "
           f"{(df['status'] == 'skipped').sum()} skipped). Means over categories of "
           f"per-category means.\n"]
    for metric in ("undersegmentation_error", "compactness"):
        out.append(f"### {METRIC_LABELS[metric]}, by number of superfacets k\n")
        out.append(_md_table(summary(df, metric), index_name="series") + "\n")
    ks = sorted(ok["n_segments"].unique())
    k = min(ks, key=lambda x: abs(x - k_focus))
    at = df[df["n_segments"] == k]
    okk = at[at["status"] == "ok"]
    rows = {}
    for name in [s for s in _series_order(df) if s in set(at["series"])]:
        sub, subok = at[at["series"] == name], okk[okk["series"] == name]
        r = {}
        for metric in METRICS:
            r[_SHORT[metric]] = (subok.groupby("category")[metric].mean().mean()
                                 if len(subok) else float("nan"))
        r["superfacets (mean)"] = subok["superfacets"].mean()
        r["iterations (mean)"] = (subok["iterations"].mean() if "iterations" in subok
                                  else float("nan"))
        conv = subok["converged"].dropna() if "converged" in subok else subok["mesh"][:0]
        r["converged"] = f"{conv.mean():.0%}" if len(conv) else ""
        r["s/mesh (mean)"] = subok["seconds"].mean()
        r["ok/failed/skipped"] = (f"{(sub['status'] == 'ok').sum()}/"
                                  f"{(sub['status'] == 'failed').sum()}/"
                                  f"{(sub['status'] == 'skipped').sum()}")
        rows[name] = r
    out.append(f"### All metrics at k = {k}\n")
    out.append(_md_table(pd.DataFrame.from_dict(rows, orient="index"), index_name="series",
                         formats={"superfacets (mean)": "{:.1f}", "iterations (mean)": "{:.1f}",
                                  "s/mesh (mean)": "{:.3f}"}) + "\n")
    out.append(f"### Per category at k = {k}: undersegmentation error / compactness\n")
    per = {}
    for metric in ("undersegmentation_error", "compactness"):
        t = okk.pivot_table(index="category", columns="series", values=metric, aggfunc="mean")
        per[metric] = t
    order = [s for s in _series_order(df) if s in per["undersegmentation_error"].columns]
    cat_rows = {}
    for cat in per["undersegmentation_error"].index:
        cat_rows[cat] = {s: f"{per['undersegmentation_error'].loc[cat, s]:.3f} / "
                            f"{per['compactness'].loc[cat, s]:.2f}" for s in order
                         if np.isfinite(per["undersegmentation_error"].loc[cat, s])}
    out.append(_md_table(pd.DataFrame.from_dict(cat_rows, orient="index")[order],
                         index_name="category") + "\n")
    k, cost = cost_table(df, k_focus)
    out.append(f"### Cost at k = {k} (seconds per segmentation from scratch)\n")
    out.append(_md_table(cost, index_name="series",
                         formats={"meshes": "{:.0f}", "faces (median)": "{:.0f}",
                                  "peak MiB (median)": "{:.0f}", "peak MiB (max)": "{:.0f}"})
               + "\n")
    failed = df[df["status"] != "ok"]
    if len(failed):
        out.append("### Rows not ok (first 20)\n")
        lines = [f"- {r.mesh} {r.series} k={r.n_segments}: {r.status}: {r.error}"
                 for r in failed.head(20).itertuples()]
        out.append("\n".join(lines) + "\n")
    return "\n".join(out)


def _save(fig, path: Path) -> Path:
    from .io import atomic_write

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
        If the file has no successful row, or a series is unknown.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    df = load_results(results, series=series)
    _ok(df)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    figs = {
        "fig4": plot_curves(df),
        "fig4_extra": plot_curves(df, ("boundary_recall", "achievable_accuracy")),
        "per_category_undersegmentation_error": plot_per_category(df, "undersegmentation_error"),
        "per_category_compactness": plot_per_category(df, "compactness"),
        "cost": plot_cost(df, k_focus),
    }
    for name, fig in figs.items():
        for ext in ("png", "svg"):
            written.append(_save(fig, out / f"{prefix}{name}.{ext}"))
        plt.close(fig)
    from .io import atomic_write

    text = markdown_summary(df, k_focus=k_focus)
    written.append(atomic_write(out / f"{prefix}summary.md", text.encode()))
    return written
