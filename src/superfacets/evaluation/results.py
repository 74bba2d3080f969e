"""The results file of experiments: its columns, a row's identity, reading and preparing it.

Row columns (:func:`columns`): ``mesh``, ``mesh_id``, ``category``, ``n_faces``,
``method``, ``elements`` (faces, vertices or points; empty in files from before: faces),
``seen_from`` (the axis a user's scan was segmented as seen from, ``experiment --inputs
--seen-from``; empty: the file's own orientation), ``n_elements``, ``n_segments`` (asked),
one column per method parameter (empty where a method does not have it), ``seed``,
``status`` (``ok``, ``failed`` or ``skipped``), ``segments`` (produced), ``iterations``,
``converged``, ``seconds`` (the method only, not reading or metrics, including work reused
from an earlier ``n_segments``), ``peak_mib`` (peak resident memory above the start of the
call, Linux only), the metrics of :data:`superfacets.evaluation.metrics.METRICS` averaged
over the mesh's ground truths, ``n_ground_truths`` and ``error``. A row is identified by
:func:`row_key`.
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Iterable

from ..errors import MeshFormatError
from ..io import atomic_write
from .methods import METHODS
from .metrics import METRICS

__all__ = ["columns", "row_key", "read_results", "prepare_file", "fmt_value", "KEY_COLUMNS"]

#: Columns naming a row, besides the method's parameters (see :func:`row_key`).
KEY_COLUMNS = ("mesh", "method", "n_segments", "seed")

_HEAD = ["mesh", "mesh_id", "category", "n_faces", "method", "elements", "seen_from",
         "n_elements", "n_segments"]
_TAIL = ["seed", "status", "segments", "iterations", "converged", "seconds", "peak_mib",
         *METRICS, "oracle_miou", "n_ground_truths", "error"]


def _param_names(configs: Iterable = ()) -> list[str]:
    names = {k for m in METHODS.values() for k in m.defaults}
    names |= {k for c in configs for k, _ in c.params}
    return sorted(names)


def columns(configs: Iterable = ()) -> list[str]:
    """Column names of a results file: fixed ones and one per method parameter."""
    return _HEAD + _param_names(configs) + _TAIL


def fmt_value(v) -> str:
    """A value as written in the results file (floats exactly, booleans as true/false)."""
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else str(v)
    return str(v)


#: Parameters added after results files were written, and the value those rows ran with.
PARAMS_BEFORE = {"tol": "0.0", "cleanup": "false", "split_merge": "false", "up_weight": "1.0",
                 "step_weight": "1.0"}


def row_key(row: dict) -> tuple:
    """The identity of a results row: mesh, method, ``n_segments``, seed, the elements, the
    axis a scan was seen from and the values of the method's parameters (all as text, as
    in the file).

    Rows of a method no longer registered are identified without parameters.
    """

    method = METHODS.get(row["method"])
    names = sorted(method.defaults) if method is not None else []
    return (tuple(str(row.get(c, "")) for c in KEY_COLUMNS)
            + (str(row.get("elements") or "faces"),)  # files from before: faces
            + (str(row.get("seen_from") or ""),)  # (a scan's side, where given)
            + tuple((n, str(row.get(n, PARAMS_BEFORE.get(n, "")))) for n in names))


def read_results(path) -> list[dict]:
    """Rows of a results file, as dicts of strings (a torn last line is dropped).

    Parameters
    ----------
    path : path

    Returns
    -------
    list of dict

    Raises
    ------
    FileNotFoundError
    superfacets.MeshFormatError
        If the file has no header row with the runner's columns.
    """
    try:
        text = Path(path).read_text(encoding="utf-8-sig")  # (a BOM: saved by a spreadsheet)
    except UnicodeDecodeError:
        raise MeshFormatError(f"{path}: not a superfacets results file (not UTF-8 text)") \
            from None
    if "\0" in text:
        raise MeshFormatError(f"{path}: not a superfacets results file (binary data)")
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]  # a row torn by a hard kill
    rows = list(csv.DictReader(io.StringIO(text)))
    for r in rows:  # files written before the column was renamed
        if "superfacets" in r:
            old = r.pop("superfacets")
            if not r.get("segments"):
                r["segments"] = old
    if text.strip() and (not rows and "method" not in text.splitlines()[0]
                         or rows and not {"mesh", "method", "status"} <= set(rows[0])):
        head = text.splitlines()[0]
        said = ("its fields are separated by ';' (a spreadsheet's export in some languages): "
                "save it with commas" if head.count(";") > head.count(",") else
                "no mesh/method/status columns")
        raise MeshFormatError(f"{path}: not a superfacets results file ({said})")
    return rows


def prepare_file(path: Path, cols: list[str]) -> tuple[list[str], list[dict]]:
    """Existing rows, the file's columns (extended if needed), torn line repaired."""

    if not path.exists() or path.stat().st_size == 0:
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerow(cols)
        atomic_write(path, buf.getvalue().encode())
        return cols, []
    raw = path.read_text()
    rows = read_results(path)
    header = next(csv.reader(io.StringIO(raw)))
    merged = header + [c for c in cols if c not in header]
    if merged != header or not raw.endswith("\n"):
        buf = io.StringIO()
        w = csv.DictWriter(buf, merged, restval="", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        atomic_write(path, buf.getvalue().encode())
    return merged, rows


