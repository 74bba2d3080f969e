"""The records of a batch's output folder: its options, its lock, the journal, the manifest.

``batch.json`` holds the options a folder was made with (:func:`record_options`;
:func:`check_options` refuses a rerun with others, so results are never mixed),
``.lock`` is there while a batch writes the folder (:class:`FolderLock`).

Each finished input is appended at once to the journal (``.manifest.jsonl``
in the output folder) by :func:`~superfacets.scale.runner.batch.run_batch`;
:func:`write_manifest` turns the rows into ``manifest.parquet`` (or
``manifest.csv`` where pyarrow is missing), atomically, and
:func:`read_manifest` reads the manifest back, updated by the journal (a line
torn by a hard kill is skipped: that input runs again).
"""

from __future__ import annotations

import json
from pathlib import Path

from ..._runtime import extras
from ..._version import __version__
from ...errors import ParameterError
from ...io.files import atomic_write

__all__ = ["MANIFEST_COLUMNS", "JOURNAL", "OPTIONS", "read_manifest", "write_manifest",
           "check_options", "record_options", "FolderLock"]

#: Columns of the manifest, in order: the input's absolute path, its labels file (relative
#: to the output folder), ok / failed / skipped, the elements labelled (faces, vertices,
#: points) and how many, the superfacets made, the passes run and whether they converged,
#: the seconds of the task (read, segment, write), the worker process's peak resident memory
#: during the task (MiB, Linux; what ``--memory-limit`` is compared with), the error's one
#: line, and when it finished (UTC); the task's warnings, one per line (none: empty).
MANIFEST_COLUMNS = ("input", "output", "status", "elements", "n_elements", "segments", "passes",
                    "converged", "seconds", "peak_mib", "error", "finished", "warnings")

_TYPES = {"n_elements": "int64", "segments": "int64", "passes": "int64", "converged": "bool",
          "seconds": "float64", "peak_mib": "float64"}
JOURNAL = ".manifest.jsonl"
OPTIONS = "batch.json"


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
        pq = extras.require("pyarrow.parquet", f"reading {pq_path}")
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


def check_options(outdir: Path, options: dict) -> bool:
    """True where ``batch.json`` records these options, False where there is none.

    Raises
    ------
    ParameterError
        The folder was made with other options (results are never mixed).
    """
    path = outdir / OPTIONS
    if not path.exists():
        return False
    try:
        before = json.loads(path.read_text()).get("options", {})
    except (ValueError, AttributeError, OSError):
        raise ParameterError(f"{path}: unreadable; remove it, or use another output "
                             "folder") from None
    if before != options:
        old, new = _flat(before), _flat(options)
        diff = ", ".join(f"{k} {old.get(k)!r} -> {new.get(k)!r}"
                         for k in sorted(set(old) | set(new)) if old.get(k) != new.get(k))
        raise ParameterError(f"{outdir}: holds results made with other options ({diff}); "
                             "use another output folder")
    return True


def _flat(d, prefix: str = "") -> dict:
    """Nested options as ``{'outputs.labels': 'seg', ...}`` (segment options unprefixed)."""
    out = {}
    for k, v in (d.items() if isinstance(d, dict) else ()):
        key = k if prefix in ("", "segment.") else prefix + k
        if isinstance(v, dict):
            out.update(_flat(v, key + "."))
        else:
            out[(prefix + k) if prefix not in ("", "segment.") else k] = v
    return out


def record_options(outdir: Path, options: dict) -> None:
    atomic_write(outdir / OPTIONS, json.dumps({"superfacets": __version__, "options": options},
                                               indent=1, sort_keys=True).encode() + b"\n")


class FolderLock:
    """An exclusive lock on a folder: a batch's output folder (one batch writes it at a
    time; another is refused with ``held`` as the reason).

    The lock file ``.lock`` is there only while a batch runs: it is removed
    before the lock is let go, and a batch that locked a file already removed
    (another batch just finished) locks the new one instead.
    """

    def __init__(self, outdir: Path, held: str = "another batch is writing this folder") -> None:
        self.path = Path(outdir) / ".lock"
        self.held = held
        self.f = None

    def __enter__(self):
        import fcntl
        import os

        while True:
            self.f = open(self.path, "a")
            try:
                fcntl.flock(self.f, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                self.f.close()
                raise ParameterError(f"{self.path.parent}: {self.held}") from None
            try:
                if os.stat(self.path).st_ino == os.fstat(self.f.fileno()).st_ino:
                    return self
            except FileNotFoundError:
                pass
            self.f.close()  # removed by the batch that held it: lock the new file

    def __exit__(self, *exc):
        try:
            self.path.unlink()
        except OSError:  # pragma: no cover - a read-only folder keeps it
            pass
        self.f.close()
