"""The manifest of a batch: one typed row per input, rebuilt from a journal.

Each finished input is appended at once to the journal (``.manifest.jsonl``
in the output folder) by :func:`~superfacets.runner.batch.run_batch`;
:func:`write_manifest` turns the rows into ``manifest.parquet`` (or
``manifest.csv`` where pyarrow is missing), atomically, and
:func:`read_manifest` reads the manifest back, updated by the journal (a line
torn by a hard kill is skipped: that input runs again).
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["MANIFEST_COLUMNS", "JOURNAL", "read_manifest", "write_manifest"]

#: Columns of the manifest, in order: the input's absolute path, its labels file (relative
#: to the output folder), ok / failed / skipped, the elements labelled (faces, vertices,
#: points) and how many, the superfacets made, the passes run and whether they converged,
#: the seconds of the task (read, segment, write), the worker process's peak resident memory
#: during the task (MiB, Linux; what ``--memory-limit`` is compared with), the error's one
#: line, and when it finished (UTC).
MANIFEST_COLUMNS = ("input", "output", "status", "elements", "n_elements", "segments", "passes",
                    "converged", "seconds", "peak_mib", "error", "finished")

_TYPES = {"n_elements": "int64", "segments": "int64", "passes": "int64", "converged": "bool",
          "seconds": "float64", "peak_mib": "float64"}
JOURNAL = ".manifest.jsonl"


def _has_pyarrow() -> bool:
    import importlib.util

    return importlib.util.find_spec("pyarrow") is not None


def _typed(row: dict) -> dict:
    """A row with every column, values of the column's type (None where empty)."""
    out = {}
    for c in MANIFEST_COLUMNS:
        v = row.get(c)
        if v == "" or v is None:
            v = None
        elif _TYPES.get(c) == "int64":
            v = int(float(v))
        elif _TYPES.get(c) == "float64":
            v = float(v)
        elif _TYPES.get(c) == "bool":
            v = v if isinstance(v, bool) else str(v).lower() == "true"
        else:
            v = str(v)
        out[c] = v
    return out


def read_manifest(outdir) -> list[dict]:
    """The rows of a batch's output folder: its manifest, updated by its journal.

    Parameters
    ----------
    outdir : path

    Returns
    -------
    list of dict
        One per input (the last row written for it), :data:`MANIFEST_COLUMNS`
        with typed values; empty when there is no manifest.

    Raises
    ------
    MissingExtraError
        When only ``manifest.parquet`` is there and pyarrow is not installed.
    """
    outdir = Path(outdir)
    rows: dict[str, dict] = {}
    pq_path, csv_path = outdir / "manifest.parquet", outdir / "manifest.csv"
    if pq_path.exists():
        from ..extras import require

        pq = require("pyarrow.parquet", f"reading {pq_path}")
        for r in pq.read_table(pq_path).to_pylist():
            rows[r["input"]] = _typed(r)
    elif csv_path.exists():
        import csv

        with open(csv_path, newline="") as f:
            for r in csv.DictReader(f):
                rows[r["input"]] = _typed(r)
    journal = outdir / JOURNAL
    if journal.exists():
        with open(journal, errors="replace") as f:
            for line in f:
                try:
                    r = json.loads(line)
                except ValueError:  # a line torn by a hard kill: that input runs again
                    continue
                if isinstance(r, dict) and r.get("input"):
                    rows[r["input"]] = _typed(r)
    return list(rows.values())


def write_manifest(outdir: Path, rows: list[dict]) -> Path:
    """Write the manifest atomically: Parquet where pyarrow is, else CSV."""
    from ..io.files import atomic_write

    rows = [_typed(r) for r in rows]
    if _has_pyarrow():
        import pyarrow as pa
        import pyarrow.parquet as pq

        types = {"int64": pa.int64(), "float64": pa.float64(), "bool": pa.bool_()}
        schema = pa.schema([(c, types.get(_TYPES.get(c), pa.string())) for c in MANIFEST_COLUMNS])
        table = pa.Table.from_pylist(rows, schema=schema)
        path = outdir / "manifest.parquet"
        atomic_write(path, lambda f: pq.write_table(table, f))
        stale = outdir / "manifest.csv"
    else:
        import csv
        import io

        buf = io.StringIO()
        w = csv.DictWriter(buf, MANIFEST_COLUMNS, lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if v is None else v) for k, v in r.items()})
        path = outdir / "manifest.csv"
        atomic_write(path, buf.getvalue().encode())
        stale = outdir / "manifest.parquet"
    if stale.exists():  # one manifest only: the other is older
        stale.unlink()
    return path
