"""Tables of experiment results: loading, per-category means, cost, Markdown.

- :func:`load_results`: the rows as a pandas DataFrame, the last row of each
  (mesh, method, parameters, ``n_segments``) kept, numbers parsed, and a
  ``series`` column naming the method and the parameters that vary;
- :func:`category_means` and :func:`summary`: per-category means, and their
  mean over categories (each category weighs the same, as in the paper);
- :func:`cost_table`, :func:`markdown_summary`: tables.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np

from ..._runtime.extras import require
from ...errors import MeshFormatError, ParameterError
from ..methods import METHODS
from ..metrics import METRICS
from ..results import PARAMS_BEFORE, read_results, row_key

__all__ = ["load_results", "category_means", "summary", "cost_table", "markdown_summary",
           "METRIC_LABELS", "segments_word", "mean_over", "FILE_KINDS"]

#: Axis labels of the metrics.
METRIC_LABELS = {
    "undersegmentation_error": "undersegmentation error (lower is better)",
    "undersegmentation_error_np": "undersegmentation error, Neubert-Protzel's (lower is "
                                  "better)",
    "compactness": "compactness (lower is better)",
    "boundary_recall": "boundary recall (higher is better)",
    "achievable_accuracy": "achievable segmentation accuracy (higher is better)",
    "seconds": "seconds per mesh",
}
_SHORT = {"undersegmentation_error": "UE", "undersegmentation_error_np": "UE (NP)",
          "compactness": "compactness",
          "boundary_recall": "boundary recall", "achievable_accuracy": "ASA",
          "oracle_miou": "oracle mIoU"}
_GREEK = {"alpha": "α", "eta_convex": "η"}



#: The columns a report draws: a word in one of them is a damaged file (elsewhere it reads
#: as no value, as before: an input's id may be a name).
DRAWN = ("n_segments", *METRICS, "oracle_miou")
#: The largest magnitude of a number a run records (counts, seconds, metrics): beyond it
#: (an infinity, 1e308) a results file is damaged, and no figure could draw it.
MOST_RECORDED = 1e100


def load_results(path, series: Sequence[str] | None = None):
    """Read a results file (or several) into a DataFrame.

    Parameters
    ----------
    path : path or sequence of paths
        CSV written by :func:`superfacets.scale.runner.run_experiment`; rows of
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
    pd = require("pandas", "making result tables")


    paths = [path] if isinstance(path, (str, Path)) else list(path)
    last = {row_key(r): r for p in paths for r in read_results(p)}  # a retried row: the last

    def filled(r: dict) -> dict:  # rows of files from before a parameter: the value they ran with
        names = METHODS[r["method"]].defaults if r["method"] in METHODS else {}
        return {**{n: v for n, v in PARAMS_BEFORE.items() if n in names}, **r}

    df = pd.DataFrame([filled(r) for r in last.values()])
    if df.empty:
        return df.assign(series=pd.Series(dtype=str))
    missing = [c for c in ("category", "n_segments") if c not in df]
    if missing:  # (a table made by hand: what the report reads is not there)
        raise MeshFormatError(f"{', '.join(map(str, paths))}: not a superfacets results file "
                              f"(no {'/'.join(missing)} column)")
    params = {m: sorted(METHODS[m].defaults) if m in METHODS else [] for m in df["method"].unique()}
    for c in ["mesh_id", "n_faces", "n_segments", "segments", "iterations", "seconds",
              "peak_mib", "n_ground_truths", "n_elements", "oracle_miou", *METRICS]:
        if c not in df:  # (a file without the column, made or cut by hand: no values)
            df[c] = float("nan")
        else:
            raw = df[c]
            df[c] = pd.to_numeric(raw, errors="coerce")
            text = raw.astype(str).str.strip().str.lower()
            worded = df[c].isna() & raw.notna() & ~text.isin(["", "nan"])
            bad = df.index[(df[c].abs() > MOST_RECORDED) | (worded & (c in DRAWN))]
            if len(bad):  # no run records an infinity, 1e308 or a word drawn: damaged
                i = bad[0]
                raise MeshFormatError(f"{', '.join(map(str, paths))}: the row of mesh "
                                      f"{df.at[i, 'mesh']!r} has {c} = {raw[i]}, which "
                                      "no run records: a damaged results file?")
    if "converged" in df:
        df["converged"] = df["converged"].map({"true": True, "false": False})
    df["series"] = _series(df, params)
    if series:
        known = set(df["series"])
        missing = [x for x in series if x not in known]
        if missing:
            raise ParameterError(f"no series {', '.join(map(repr, missing))}; present: "
                                 f"{', '.join(map(repr, series_order(df)))}")
        df = df[df["series"].isin(series)].reset_index(drop=True)
    return df


def _series(df, params: dict):
    out = df["method"].copy()
    for m, names in params.items():
        sel = df["method"] == m
        varying = [p for p in [*names, "seen_from"]
                   if p in df and df.loc[sel, p].fillna("").nunique() > 1]
        if not varying:
            continue
        vals = df.loc[sel, varying].fillna("").apply(
            lambda r: " ".join(f"{_GREEK.get(p, p)}={_label(p, r[p])}" for p in varying),
            axis=1)
        out[sel] = m + " " + vals
    return out


def _label(name: str, text: str) -> str:
    """A parameter's value in a series' name; a scan's side not given: ``file`` (the
    file's own orientation)."""
    return _num(text) if text != "" or name != "seen_from" else "file"


def _num(text: str) -> str:
    try:
        x = float(text)
    except (TypeError, ValueError):
        return str(text)
    return f"{x:g}"


def series_order(df) -> list[str]:
    """Series sorted by method (first appearance), then numerically by parameter values."""
    order = []
    for m in dict.fromkeys(df["method"]):
        names = sorted(df.loc[df["method"] == m, "series"].unique(), key=_natural)
        order += names
    return order


def _natural(s: str):
    import re

    # numbers before words at the same place, so mixed values ("auto", 0.05) still sort
    return [(0, float(t), "") if re.fullmatch(r"-?\d+(\.\d+)?", t) else (1, 0.0, t)
            for t in re.split(r"=| ", s)]


def ok_rows(df):
    """The rows of status ``ok``; ParameterError when there are none."""
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
    ok = ok_rows(df)
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
    return s.reindex([x for x in series_order(df) if x in s.index])



#: The categories of rows from a user's files (``experiment --inputs``): their kind
FILE_KINDS = ("cloud", "mesh", "volume")


def segments_word(df) -> str:
    """The rows' word for their segments (the kinds' table's: superpoints of points,
    superfacets of faces), ``segments`` where the rows hold kinds of both words.

    Parameters
    ----------
    df : pandas.DataFrame
        From :func:`load_results`.

    Returns
    -------
    str

    Raises
    ------
    ParameterError
        If no row is ok (:func:`ok_rows`).

    Examples
    --------
    >>> import pandas as pd
    >>> segments_word(pd.DataFrame({"status": ["ok"], "elements": ["points"]}))
    'superpoints'
    """
    from ...elements.kinds import KINDS

    ok = ok_rows(df)
    kinds = set(ok["elements"].dropna()) if "elements" in ok else set()
    words = {KINDS[k].segment_word for k in kinds if k in KINDS} or {"superfacets"}
    return words.pop() if len(words) == 1 else "segments"


def mean_over(df) -> str:
    """What a curve's and a table's values are the mean over: the benchmark's categories,
    or a user's inputs (each kind of input weighing the same where there are several).

    Parameters
    ----------
    df : pandas.DataFrame
        From :func:`load_results`.

    Returns
    -------
    str

    Raises
    ------
    ParameterError
        If no row is ok (:func:`ok_rows`).

    Examples
    --------
    >>> import pandas as pd
    >>> mean_over(pd.DataFrame({"status": ["ok"] * 2, "category": ["cloud"] * 2,
    ...                         "mesh": ["a", "b"]}))
    'mean over 2 inputs'
    """
    ok = ok_rows(df)
    cats = set(ok["category"])
    if cats <= set(FILE_KINDS):
        n = ok["mesh"].nunique()
        inputs = f"{n} input{'' if n == 1 else 's'}"
        return (f"mean over {inputs}" if len(cats) == 1 else
                f"mean over {inputs}, each of the {len(cats)} kinds ({', '.join(sorted(cats))})"
                " weighing the same")
    return f"mean over {len(cats)} categor{'y' if len(cats) == 1 else 'ies'}"


def rows_at_k(df, k_focus: int):
    """``(k, rows)``: the ok rows at the ``n_segments`` nearest ``k_focus``."""
    ok = ok_rows(df)
    ks = sorted(ok["n_segments"].unique())
    k = min(ks, key=lambda x: abs(x - k_focus))
    return k, ok[ok["n_segments"] == k]


def cost_table(df, k_focus: int = 150):
    """Per series at ``k_focus``: median and largest seconds and peak MiB, meshes.

    Returns
    -------
    pandas.DataFrame
    """
    pd = require("pandas", "making result tables")

    k, at = rows_at_k(df, k_focus)
    rows = {}
    for name in [s for s in series_order(df) if s in set(at["series"])]:
        sub = at[at["series"] == name]
        r = {"meshes": sub["mesh"].nunique()}
        if sub["n_faces"].notna().any() or "n_elements" not in sub:
            r["faces (median)"] = sub["n_faces"].median()
        else:  # (a user's clouds and volumes: their elements)
            r["elements (median)"] = sub["n_elements"].median()
        r.update({"s (median)": sub["seconds"].median(), "s (max)": sub["seconds"].max()})
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
    pd = require("pandas", "making result tables")

    ok = ok_rows(df)
    files = set(ok["category"]) <= set(FILE_KINDS)
    n_cat = ok["category"].nunique()
    what = (f"{ok['mesh'].nunique()} inputs" if files else
            f"{ok['mesh'].nunique()} meshes, {n_cat} categor{'y' if n_cat == 1 else 'ies'}")
    out = [f"Results: {what}, {len(df)} rows ({len(ok)} ok, "
           f"{(df['status'] == 'failed').sum()} failed, "
           f"{(df['status'] == 'skipped').sum()} skipped). Values: the {mean_over(df)}"
           f"{'' if files and n_cat == 1 else ' (of per-category means)'}.\n"]
    word = segments_word(df)
    for metric in ("undersegmentation_error", "compactness"):
        out.append(f"### {METRIC_LABELS[metric]}, by number of {word} k\n")
        out.append(_md_table(summary(df, metric), index_name="series") + "\n")
    ks = sorted(ok["n_segments"].unique())
    k = min(ks, key=lambda x: abs(x - k_focus))
    at = df[df["n_segments"] == k]
    okk = at[at["status"] == "ok"]
    rows = {}
    for name in [s for s in series_order(df) if s in set(at["series"])]:
        sub, subok = at[at["series"] == name], okk[okk["series"] == name]
        r = {}
        for metric in [*METRICS, *(["oracle_miou"] if "oracle_miou" in at else [])]:
            r[_SHORT[metric]] = (subok.groupby("category")[metric].mean().mean()
                                 if len(subok) else float("nan"))
        r["segments (mean)"] = subok["segments"].mean()
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
                         formats={"segments (mean)": "{:.1f}", "iterations (mean)": "{:.1f}",
                                  "s/mesh (mean)": "{:.3f}"}) + "\n")
    out.append(f"### Per category at k = {k}: undersegmentation error / compactness\n")
    per = {}
    for metric in ("undersegmentation_error", "compactness"):
        t = okk.pivot_table(index="category", columns="series", values=metric, aggfunc="mean")
        per[metric] = t
    order = [s for s in series_order(df) if s in per["undersegmentation_error"].columns]
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
                                  "elements (median)": "{:.0f}",
                                  "peak MiB (median)": "{:.0f}", "peak MiB (max)": "{:.0f}"})
               + "\n")
    failed = df[df["status"] != "ok"]
    if len(failed):
        out.append("### Rows not ok (first 20)\n")
        lines = [f"- {r.mesh} {r.series} k={r.n_segments}: {r.status}: {r.error}"
                 for r in failed.head(20).itertuples()]
        out.append("\n".join(lines) + "\n")
    return "\n".join(out)
