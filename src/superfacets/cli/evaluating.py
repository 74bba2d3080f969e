"""``superfacets evaluate``: the metrics of a label file against ground truths.

Faces of a mesh (area weighted, the paper's metrics), or its vertices, or
the points of a cloud (a labelled scan: each element counted once,
unlabelled ones left out with ``--ignore-label``); ground truths from
``.seg`` files or from a field of the input file itself (a LAS file's
``classification``, a PLY's vertex ``label``).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..checks import counted
from ..elements.kinds import kind_of
from ..method.params import DEFAULTS
from .options import elements_of_input, float_arg, int_arg, read_usable, refuse_neighbours

__all__ = ["add_parsers", "cmd_evaluate"]


def add_parsers(sub) -> None:
    e = sub.add_parser(
        "evaluate", help="metrics of a segmentation against ground truths",
        description="Print the undersegmentation error (eq. 4), compactness (eq. 5), boundary "
                    "recall and precision and achievable segmentation accuracy of a label file, "
                    "each averaged "
                    "over the given ground-truth segmentations: area-weighted on the faces of "
                    "a mesh; each element counted once on its vertices (--elements vertices) "
                    "or the points of a cloud (a labelled scan). With no ground truth, the "
                    "compactness and the segments' sizes alone. The labels are a file "
                    "(LABELS) or a field of the input (--labels-from FIELD); with the "
                    "latter, every file named after INPUT is a ground truth.")
    e.add_argument("mesh", metavar="INPUT", help="the mesh or point-cloud file")
    e.add_argument("labels", metavar="LABELS", nargs="?", default=None,
                   help="labels, one per face (vertex, point) in file order: a .seg file, a "
                        "segIndices .json, or a PLY, PCD or LAS/LAZ written by 'segment -o' "
                        "(its ClusterID)")
    e.add_argument("--labels", metavar="LABELS", dest="labels_file", default=None,
                   help="LABELS given by name (the same file)")
    e.add_argument("--labels-from", metavar="FIELD", default=None,
                   help="instead of LABELS, the labels in a field of the input itself: a "
                        "LAS/LAZ dimension, a PLY vertex property (scalar_NAME found as NAME), "
                        "a PCD field or a field of NPY records (ClusterID, or a level's "
                        "ClusterID_N, as 'segment --levels ... -o OUT.laz' writes them)")
    e.add_argument("ground_truths", metavar="GT.seg", nargs="*",
                   help="ground truths of the same input (none: the shapes alone), one per "
                        "face (vertex, "
                        "point): label files as -o writes them, SemanticKITTI's .label or "
                        "nuScenes' _lidarseg.bin")
    e.add_argument("--ground-truth", metavar="GT.seg", action="append", default=None,
                   dest="ground_truth_files",
                   help="a ground-truth file given by name (as GT.seg after LABELS; may "
                        "repeat)")
    e.add_argument("--ground-truth-field", metavar="NAME", default=None,
                   help="also a ground truth read from the input file itself: a LAS/LAZ "
                        "dimension (classification), a PLY vertex property (ScanNet's "
                        "label), a PCD field (PCL's label), a field of NPY records or a "
                        "text cloud's named column (CloudCompare's //X;Y;Z;Classification)")
    e.add_argument("--tau", type=float_arg, default=0.05,
                   help="overlap tolerance of the undersegmentation error, a fraction of each "
                        "superfacet's area (default: 0.05)")
    e.add_argument("--elements", choices=("faces", "vertices"), default=None,
                   help="what a mesh's labels are of (default: faces; a cloud's are of points)")
    e.add_argument("--neighbors", type=int_arg, default=DEFAULTS.n_neighbors, metavar="N",
                   help="point clouds: nearest neighbours of the graph the metrics are "
                        f"measured on (default: {DEFAULTS.n_neighbors})")
    e.add_argument("--ignore-label", type=int_arg, default=None, metavar="L",
                   help="a ground-truth value meaning unlabelled (e.g. -1, or 0 for "
                        "SemanticKITTI): those elements are left out of the metrics")
    fmt = e.add_mutually_exclusive_group()
    fmt.add_argument("--json", dest="format", action="store_const", const="json",
                     default="text", help="print one JSON object (input, elements, counts, "
                                          "metrics) for scripts")
    fmt.add_argument("--csv", dest="format", action="store_const", const="csv",
                     help="print a CSV header line and one row, for scripts and spreadsheets")
    e.set_defaults(func=cmd_evaluate, late_files=("labels", "ground_truths"))


def cmd_evaluate(args) -> int:
    from .._runtime.progress import waiting_bar
    from ..errors import ParameterError
    from ..evaluation.metrics import evaluate_rows, shape_rows
    from ..io import read_labels
    from .reading import shows_stages

    if not (0 <= args.tau < 1):
        raise ParameterError(f"--tau must be in [0, 1), got {args.tau}")
    name = Path(args.mesh).name  # (long stages on a terminal: a line, its time going on)
    with waiting_bar(f"reading {name}", shows_stages(args, path=args.mesh)):
        data = read_usable(args.mesh, clouds=True)  # area-weighted metrics: a measurable mesh
    own = elements_of_input(data)  # faces (a mesh), points (a cloud), cells (tetrahedra)
    if own != "faces" and args.elements not in (None, own):
        what = "a point cloud" if own == "points" else "a tetrahedral mesh"
        raise ParameterError(f"{args.mesh} is {what}: its labels are of its "
                             f"{kind_of(own).noun} (--elements {own}), not {args.elements}")
    kind = args.elements or own
    refuse_neighbours(args.neighbors, None, kind)
    n = kind_of(kind).n_rows(data)
    long = shows_stages(args, n)
    if args.labels_from is not None and args.labels is not None:  # (all ground truths)
        args.ground_truths, args.labels = [args.labels, *args.ground_truths], None
    with waiting_bar(f"reading the labels of {kind_of(kind).counted(n)}", long):
        labels, said = _labels_of(args, data, kind)
        gts = [_counted(read_labels(p), p, args, data, kind) for p in args.ground_truths]
    if labels.size and (labels < 0).all():  # (the oracle mIoU said "no labelled element")
        raise ParameterError(f"{said}: every label is below 0 (unassigned, as DBSCAN's "
                             "noise): no segment to measure")
    if args.ground_truth_field is not None:
        from ..io.labels import read_field

        _check_field_name(args.ground_truth_field)
        gt = read_field(args.mesh, args.ground_truth_field)
        if gt.shape[0] != n:
            raise ParameterError(f"field {args.ground_truth_field!r} has {gt.shape[0]:,} "
                                 f"values but {args.mesh} has {kind_of(kind).counted(n)}")
        gts.append(gt)
    judged = [f for f, on in (("--tau", args.tau != 0.05),
                              ("--ignore-label", args.ignore_label is not None)) if on]
    if judged and not gts:  # (the shapes alone: nothing judged against a truth)
        raise ParameterError(f"{' and '.join(judged)} judge{'s' if len(judged) == 1 else ''} "
                             "against a ground truth: give GT.seg files or "
                             "--ground-truth-field NAME")
    with waiting_bar(f"measuring {name} ({kind_of(kind).counted(n)})", long):
        if gts:
            m = evaluate_rows(data, labels, gts, elements=kind, n_neighbors=args.neighbors,
                              tau=args.tau, ignore_label=args.ignore_label, precision=True)
            m["class_names"] = _class_names(args, len(gts))
        else:  # (the segments' shapes alone: every other metric compares with a truth)
            m = dict(dict.fromkeys(METRICS), oracle_iou_per_class={}, **shape_rows(
                data, labels, elements=kind, n_neighbors=args.neighbors))
    if args.format != "text":
        _print_table(args, kind, n, len(gts), m)
        return 0
    segs = counted(int(m["segments"]), kind_of(kind).segment_word[:-1])
    valid = getattr(data, "valid", None) if kind_of(kind).cloud else None
    invalid = 0 if valid is None else int((~np.asarray(valid)).sum())
    said = f" ({invalid:,} invalid, not measured)" if invalid else ""
    print(f"{Path(args.mesh).name}: {kind_of(kind).counted(n)}{said}, {segs}, "
          f"{len(gts) or 'no'} ground truth{'s' if len(gts) != 1 else ''}")
    if gts:
        print(f"undersegmentation_error {m['undersegmentation_error']:.4f}  (lower is better)")
        print(f"  Neubert-Protzel's     {m['undersegmentation_error_np']:.4f}  (lower is "
              "better; no tolerance: a segment that swallows small classes pays for them)")
    estimate = "; estimated on points" if kind_of(kind).cloud else ""
    print(f"compactness             {m['compactness']:.4f}  (lower is better; disk 3.545"
          f"{estimate})")
    if gts:
        _print_truth_metrics(m, n, kind)
    else:
        print("note: with no ground truth only the shapes are measured; give GT.seg files "
              "or --ground-truth-field NAME for the error, recall, precision and mIoU")
    if m.get("unassigned"):
        print(f"note: {kind_of(kind).counted(m['unassigned'])} labelled below 0 (unassigned): "
              "each such label counts as one segment")
    hist = ", ".join(f"{2**i}+: {c}" for i, c in enumerate(m["size_histogram"]) if c)
    print(f"segment sizes           {m['size_min']} / {m['size_median']:g} / "
          f"{m['size_max']} {kind_of(kind).noun} (min / median / max; by size {hist})")
    return 0


def _class_names(args, n_truths: int) -> dict:
    """The names of the classes of the one ground truth, where it is a field its format
    names (a LAS file's ``classification``: the ASPRS classes); else none."""
    from ..io.labels import class_names

    field = args.ground_truth_field
    return class_names(args.mesh, field) if field is not None and n_truths == 1 else {}


def _print_truth_metrics(m: dict, n: int, kind: str) -> None:
    """The lines of the metrics that compare with the ground truths (after the
    compactness)."""
    print(f"boundary_recall         {m['boundary_recall']:.4f}  (higher is better)")
    print(f"boundary_precision      {m['boundary_precision']:.4f}  (higher is better; read "
          "with the recall)")
    print(f"achievable_accuracy     {m['achievable_accuracy']:.4f}  (higher is better)")
    print(f"oracle_miou             {m['oracle_miou']:.4f}  (higher is better; each segment "
          "given its majority class)")
    per_class = m.get("oracle_iou_per_class", {})
    names = m.get("class_names", {})
    if len(per_class) <= MOST_CLASSES_LISTED:
        for cls, iou in sorted(per_class.items()):
            named = f"{names[int(cls)]:<25}" if int(cls) in names else ""
            print(f"  class {cls:<6} {named}IoU {iou:.4f}")
    else:
        print(f"  {len(per_class):,} classes: each one's IoU with --json")
    if len(per_class) > n // 2 >= MOST_CLASSES_LISTED:  # (a coordinate, an identifier)
        print(f"note: the ground truth has {len(per_class):,} classes for "
              f"{kind_of(kind).counted(n)}: is it a field of labels?")
    if len(per_class) == 1:
        print(f"note: the ground truth has one class ({next(iter(per_class))}) here: it has "
              "no border, so the recall and precision say nothing")
    elif m.get("borderless_truths"):
        noun = kind_of(kind).noun
        print(f"note: no two neighbouring {noun} differ in {m['borderless_truths']} of the "
              f"ground truths (their classes lie on separate pieces of the {noun}' graph): "
              "there the recall is 1 and the precision 0 by convention, and say nothing")
    below = sorted(int(c) for c in per_class if int(c) < 0)
    if below:
        print(f"note: class {', '.join(map(str, below))} measured as a class; if it marks "
              f"unlabelled {kind_of(kind).noun}, --ignore-label {below[0]} leaves them out")


#: The most classes whose IoU the text output lists one by one (more: with --json).
MOST_CLASSES_LISTED = 40

#: The metrics printed, in order.
METRICS = ("undersegmentation_error", "undersegmentation_error_np", "compactness",
           "boundary_recall", "boundary_precision", "achievable_accuracy", "oracle_miou")


def _labels_of(args, data, kind: str):
    """The labels judged, from LABELS or ``--labels-from FIELD``, and what names them."""
    from ..errors import ParameterError
    from ..io import read_labels
    from ..io.labels import read_field

    field = args.labels_from
    if field is None and args.labels is None:
        raise ParameterError("give the labels: LABELS (a file) or --labels-from FIELD (a field "
                             "of the input, as ClusterID)")
    if field is None:
        return _counted(read_labels(args.labels), args.labels, args, data, kind), args.labels
    said = f"{Path(args.mesh).name}: {field}"
    return _counted(read_field(args.mesh, field), said, args, data, kind), said


def _counted(labels, path, args, data, kind: str):
    """``labels`` read from ``path``, refused in words where they are not one per element
    of ``kind`` (naming the input, and ``--elements vertices`` where they are one per
    vertex of a mesh whose faces are judged)."""
    from ..errors import MeshFormatError

    n = kind_of(kind).n_rows(data)
    if labels.shape[0] == n:
        return labels
    hint = ("; they are one per vertex: --elements vertices" if kind == "faces"
            and labels.shape[0] == getattr(data, "n_vertices", -1) else "")
    raise MeshFormatError(f"{path}: {labels.shape[0]:,} labels, but {args.mesh} has "
                          f"{kind_of(kind).counted(n)} (one label per "
                          f"{kind_of(kind).singular} is needed){hint}")


def _check_field_name(name: str) -> None:
    """Refuse a ground-truth file given as ``--ground-truth-field``: the option names a
    field of the input (a file is ``--ground-truth GT.seg``, or GT.seg after LABELS)."""
    from ..errors import ParameterError

    if Path(name).suffix.lower() in (".seg", ".json", ".txt", ".gz", ".xz") or \
            os.path.sep in name or Path(name).is_file():
        raise ParameterError(f"--ground-truth-field names a field of the input file (e.g. "
                             f"classification), not a file ({name!r}); give a ground-truth "
                             f"file after the labels: superfacets evaluate INPUT LABELS {name} (or "
                             f"--ground-truth {name})")


def _print_table(args, kind: str, n: int, n_truths: int, m: dict) -> None:
    """The metrics as one JSON object or one CSV row (with its header line)."""
    import csv
    import json
    import sys

    judged = Path(args.labels).name if args.labels else args.labels_from
    row = {"input": Path(args.mesh).name, "labels": judged,
           "elements": kind, "n_elements": int(n), "segments": int(m["segments"]),
           "ground_truths": int(n_truths), "tau": float(args.tau),
           **{k: None if m[k] is None else float(m[k]) for k in METRICS},
           **{k: m[k] for k in ("size_min", "size_median", "size_max", "unassigned")}}
    if args.format == "json":
        row["oracle_iou_per_class"] = {str(k): v for k, v in
                                       m.get("oracle_iou_per_class", {}).items()}
        names = m.get("class_names", {})
        row["class_names"] = {str(k): names[int(k)] for k in row["oracle_iou_per_class"]
                              if int(k) in names}
        row["size_histogram"] = m["size_histogram"]
        row["borderless_truths"] = m.get("borderless_truths", 0)
    if args.format == "json":
        print(json.dumps(row, indent=2))
        return
    out = csv.DictWriter(sys.stdout, fieldnames=list(row), lineterminator="\n")
    out.writeheader()
    out.writerow(row)
