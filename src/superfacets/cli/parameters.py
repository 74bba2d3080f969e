"""The method's options, made from :data:`superfacets.method.params.PARAMETERS`.

Each parameter of the method is declared once (its name, default, check and option);
this module adds only how the command line shows it (a metavar, a longer help where the
one-line ``doc`` does not say enough, the group of ``--help`` it stands in) and builds
both the options and the keyword arguments of a run from the declarations. A parameter
declared with an option but shown nowhere here still gets its option, with its ``doc``
as help: nothing declared is dropped (``tests/cli/test_cli.py`` sends every parameter from
the command line and checks that it reaches the run).
"""

from __future__ import annotations

import argparse

from ..method.params import (
    COARSE_MIN_PER_SEGMENT,
    COARSE_MIN_PER_SEGMENT_POINTS,
    COARSE_PER_SEGMENT,
    DEFAULTS,
    PARAMETERS,
    WEIGHTING_ALPHA,
)
from ..method.params import DEFAULT_CENTER_TOL as _D_CENTER_TOL

__all__ = ["GROUPS", "SHOWN", "ELEMENT_PARAMETERS", "add_parameters", "parameter_kwargs",
           "int_arg", "float_arg", "auto_float_arg"]

_D = DEFAULTS

#: The groups of ``--help`` the parameters stand in, by key
GROUPS = {"size": "how many", "method": "the method", "elements": "what is segmented",
          "clouds": "point clouds", "run": "the run"}

#: How the command line shows a parameter: group, metavar (or the flag's style: ``switch``
#: a flag that sets True, ``negated`` an option ``--no-...`` that sets False, ``both``
#: ``--x/--no-x`` whose absence leaves the method to decide) and help.
SHOWN = {
    "n_segments": ("size", "N", f"number of superfacets k (default: {_D.n_segments} unless "
                   "--radius is given)"),
    "radius": ("size", "R", "superfacet radius as a fraction of the bounding-box diagonal "
               "(instead of -k; default init then 'flood')"),
    "alpha": ("method", "A", "weight of the concavity (angular) term, >= 0; 0 = most "
              f"compact, larger = follows concavities more (default: {_D.alpha:g})"),
    "eta_convex": ("method", "E", "factor of the angular term on convex edges (concave: 1) "
                   f"(default: {_D.eta_convex:g})"),
    "init": ("method", None, "initialization (default: farthest with -k, flood with "
             "--radius)"),
    "window": ("method", "W", "expansion window, a multiple of the radius (default: "
               f"{_D.window:g})"),
    "max_iter": ("method", "N", f"maximum number of iterations (default: {_D.max_iter})"),
    "weighting": ("method", None, "edge weights: the paper's eqs. 1-3 or Shlafman's eq. 6 "
                  f"(then --alpha in [0, 1]) (default: {_D.weighting})"),
    "assignment": ("method", None, "bounded: the paper's window-bounded expansion per "
                   "center; exact: nearest center by one multi-source search (default: "
                   "exact on vertices and points, bounded on faces; --paper: bounded)"),
    "enforce_connectivity": ("method", "negated", "keep superfacets split in several "
                             "pieces (default: merge stray pieces into the neighbour sharing "
                             "the longest boundary)"),
    "cleanup": ("method", "both", "boundary clean-up after the iteration: boundaries "
                "straightened and moved onto nearby creases, same superfacets (default: on "
                "for faces and vertices, off for points, --paper and --weighting shlafman)"),
    "split_merge": ("method", "both", "split superfacets that straddle a crease and merge "
                    "as many pairs of neighbours elsewhere, then iterate again; same number "
                    "of superfacets (default: on for faces and vertices, off for points, "
                    "--paper and --weighting shlafman)"),
    "tol": ("method", "T", "also stop once a pass changes the superfacet of at most this "
            f"fraction of the area (default: {_D.tol:g}; 0: the paper's rule: stop when no "
            "center moves, and --center-tol 0 --coarsen 1 unless given; --paper for the "
            "paper's labels bit for bit)"),
    "center_tol": ("method", "F", "a center the update would move by less than this "
                   "fraction of the superfacet radius stays where it is (default: "
                   f"{_D_CENTER_TOL:g}, 0 with --tol 0)"),
    "coarsen": ("method", "N", "coarse-to-fine: first solve on clusters of about N "
                "elements, then refine on all of them; 1: off (default: on where a "
                f"superfacet holds at least {COARSE_MIN_PER_SEGMENT:,} elements, leaving "
                f"about {COARSE_PER_SEGMENT:,} clusters per superfacet; for points from "
                f"{COARSE_MIN_PER_SEGMENT_POINTS:,} points per superpoint, clusters of at "
                "most n_neighbors / 2 points; off with --tol 0)"),
    "beta": ("method", "B", "weight of the colour term: crossing a colour edge costs as "
             "crossing a crease does (the input's RGB: PLY, PCD or LAS points, a mesh's "
             "vertex or face colours); auto: differences within the colours' noise cost "
             "nothing and the rest weighs on average as much as distance and angle; 0: off "
             "(default: auto where the input has colours)"),
    "min_elements": ("method", "N", "merge superfacets (superpoints) of fewer than N faces "
                     "(vertices, points) into a neighbour at the end; the count falls by "
                     f"those merged (default: {_D.min_elements}, none)"),
    "density": ("method", "Q", "content-sensitive sizes: 0 superfacets of equal area (the "
                "paper), 1 of equal numbers of elements; auto: 0.5 on point clouds of "
                "uneven density (LiDAR sweeps, RGB-D frames), else 0 (default: auto)"),
    "roughness": ("method", "C", "content-sensitive sizes: smaller superfacets where "
                  "neighbouring normals turn (C per radian of mean angle); 1 suits scans "
                  f"(default: {_D.roughness:g})"),
    "merge_from": ("method", "F", "segment F times -k superpoints first, then merge "
                   "neighbours down to -k, flat ones (within the noise) first; 1: off "
                   "(default: 5 on point clouds, 20 on scenes with an up direction: "
                   "LAS, LAZ, E57, RGB-D frames, --seen-from; 1 on meshes; with "
                   "--merge-cost auto 1 on clouds of uneven density)"),
    "max_size_ratio": ("method", "R", "with --merge-from above 1: the merges make no "
                       "superpoint of more than R times the mean count of points while other "
                       "neighbours can merge (flat ground and walls in several superpoints, "
                       "not one); 0: no bound (default: 4 on scenes with an up direction, "
                       "16 elsewhere)"),
    "merge_cost": ("method", None, "the merges to -k: noise by one cost on scans, the "
                   "plane's rise in the noise's units, weighted by the noise's share of the "
                   "superpoints' residual, plus Ward's, merging every cloud, uneven density "
                   "too (auto's merges on noise-free surfaces); auto (the default before "
                   "2026-11-30) by the plane's rise where flat regions hold most of the "
                   "points, else by Ward's cost, no merges on uneven density; scene: noise's "
                   "cost, the rise unweighted, worse on noise-free sampled surfaces "
                   f"(default: {_D.merge_cost})"),
    "paper": ("method", "switch", "the paper's method as published, its labels bit for bit: "
              "its stopping rule (--tol 0), no clean-up, no split-and-merge (the default on "
              "faces adds both: lower undersegmentation error and more compact superfacets "
              "at the paper's speed)"),
    "elements": ("elements", None, "segment the faces of a mesh (the paper), its vertices "
                 "(one label per vertex, like the ScanNet Segmentator) or the points of a "
                 "cloud (default: points for a point cloud, faces for a mesh)"),
    "n_neighbors": ("clouds", "N", "nearest neighbours of each point (default: "
                    f"{_D.n_neighbors})"),
    "neighbor_radius": ("clouds", "R", "drop neighbours farther than this fraction of the "
                        "bounding-box diagonal (default: none)"),
    "up_weight": ("clouds", "W", "weigh the cloud's up coordinate (a LAS, LAZ or E57 file's z; "
                  "--seen-from AXIS for others) W times in the method's distances, > 0; 1: off "
                  "(default: read from a scene's surfaces, 1 to 8 the more its planes lie "
                  "level: 3-8 on airborne scans, keeping ground, vegetation and roofs "
                  "apart; 1 in rooms and on clouds with no up)"),
    "step_weight": ("clouds", "S", "weigh a step off the surface (a neighbour's offset along "
                    "the normals) S times in the choice of neighbours and in the distances, "
                    ">= 1: a roof apart from the ground, a table from the floor (default: 4 "
                    "on a scene, a cloud with an up direction; 1 elsewhere)"),
    "n_threads": ("run", "N", "threads of the run: graph build, expansions, split-and-merge "
                  "searches, clean-up cuts (default: all cores; the labels do not depend on "
                  "it)"),
    "progress": ("run", "both", "progress bar of the stages and iterations on stderr "
                 "(default: on for meshes of 500,000 faces or more when stderr is a "
                 "terminal)"),
}

#: The parameters of what is segmented (``add_element_options``); the others are the
#: method's (``add_method_options``)
ELEMENT_PARAMETERS = ("elements", "n_neighbors", "neighbor_radius")


def int_arg(text: str) -> int:
    """argparse type: an integer."""
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def float_arg(text: str) -> float:
    """argparse type: a number."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


def int_list_arg(text: str) -> list[int]:
    """argparse type of a ``nargs="+"`` option with :class:`Joined`: integers, also
    comma-separated (``-k 100,300`` as ``-k 100 300``: ``--levels`` and ``--param`` take
    commas)."""
    return [int_arg(t) for t in text.split(",") if t.strip()] or [int_arg(text)]


def float_list_arg(text: str) -> list[float]:
    """As :func:`int_list_arg`, numbers."""
    return [float_arg(t) for t in text.split(",") if t.strip()] or [float_arg(text)]


class Joined(argparse.Action):
    """A ``nargs="+"`` option whose values are lists (:func:`int_list_arg`): one list."""

    def __call__(self, parser, namespace, values, option_string=None):
        setattr(namespace, self.dest, [v for value in values for v in value])


def auto_float_arg(text: str) -> float | None:
    """argparse type: a number, or ``auto`` (None: the method decides)."""
    return None if text.strip().lower() == "auto" else float_arg(text)


def _dest(p) -> str:
    return p.cli.lstrip("-").replace("-", "_")


def _parse(p):
    """The text -> value conversion of a valued option, from the declared type."""
    if p.choices:
        return None
    if p.type.startswith("int"):
        return int_arg
    if p.name in ("density", "beta"):  # (None is spelled "auto")
        return auto_float_arg
    return float_arg


def add_parameters(parser, names, *, groups: bool = True) -> None:
    """Add the options of the parameters ``names`` (declaration order) to ``parser``,
    each in its ``--help`` group where ``groups``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    names : collection of str
        Names of :data:`~superfacets.method.params.PARAMETERS` entries.
    groups : bool, default True

    Examples
    --------
    >>> import argparse
    >>> p = argparse.ArgumentParser()
    >>> add_parameters(p, ("alpha", "paper"))
    >>> a = p.parse_args(["--alpha", "50", "--paper"])
    >>> parameter_kwargs(a, ("alpha", "paper"))
    {'alpha': 50.0, 'paper': True}
    """
    made: dict[str, object] = {}

    def where(key: str):
        if not groups:
            return parser
        if key not in made:
            group = parser.add_argument_group(GROUPS[key])  # (-k or --radius: one of them)
            made[key] = group.add_mutually_exclusive_group() if key == "size" else group
        return made[key]

    for p in PARAMETERS:
        if p.name not in names or p.cli is None:
            continue
        group, style, text = SHOWN.get(p.name, ("method", None, p.doc))
        opts = ("-k", p.cli) if p.name == "n_segments" else (p.cli,)
        kw = dict(dest=_dest(p), help=text)
        if style == "switch" or style == "negated":
            kw.update(action="store_true")
        elif style == "both":
            kw.update(action=argparse.BooleanOptionalAction, default=None)
        else:
            default = None if p.name in ("n_segments", "alpha") else p.default  # (alpha:
            # the weighting's own, resolved by superfacets.method.params.resolve)
            kw.update(default=default, metavar=style, type=_parse(p))
            if p.choices:
                kw.update(choices=p.choices)
                kw.pop("metavar")
        where(group).add_argument(*opts, **kw)


def parameter_kwargs(args, names) -> dict:
    """The keyword arguments of :func:`superfacets.segment` for the parameters ``names``
    from the options :func:`add_parameters` made (a negated flag given: False).

    Examples
    --------
    >>> import argparse
    >>> p = argparse.ArgumentParser()
    >>> add_parameters(p, ("enforce_connectivity", "n_threads"))
    >>> parameter_kwargs(p.parse_args(["--no-connectivity"]),
    ...                  ("enforce_connectivity", "n_threads"))
    {'enforce_connectivity': False, 'n_threads': None}
    """
    out = {}
    for p in PARAMETERS:
        if p.name not in names or p.cli is None:
            continue
        value = getattr(args, _dest(p))
        style = SHOWN.get(p.name, ("", None, ""))[1]
        out[p.name] = (not value) if style == "negated" else value
    if "progress" in out:
        out["progress"] = bool(out["progress"])
    if "alpha" in out and out["alpha"] is None:  # the weighting's own (Shlafman's: 0.5)
        out["alpha"] = WEIGHTING_ALPHA.get(out.get("weighting") or "paper", (None,))[0]
    return out
