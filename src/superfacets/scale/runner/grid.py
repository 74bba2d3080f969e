"""Parameter grids of experiments: every combination of the values given per parameter."""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np

from ...errors import ParameterError
from ...evaluation.methods import Method, get_method
from ...evaluation.results import fmt_value

__all__ = ["Config", "expand_grid", "parse_params", "method_grid"]


@dataclass(frozen=True)
class Config:
    """One method with all its parameters resolved (``n_segments`` excepted)."""

    method: str
    params: tuple  # sorted (name, value) pairs

    @property
    def kwargs(self) -> dict:
        return dict(self.params)

    def label(self) -> str:
        return self.method + "".join(f" {k}={fmt_value(v)}" for k, v in self.params)


def expand_grid(method: str, **values) -> list[Config]:
    """Every combination of the given parameter values for one method.

    Parameters
    ----------
    method : str
        A registered method name.
    **values : sequence or scalar
        Values per parameter; parameters not given take their default.

    Returns
    -------
    list of Config

    Raises
    ------
    ParameterError
        On an unknown method or parameter, or an empty list of values.

    Examples
    --------
    >>> [c.label().split()[:2] for c in expand_grid("superfacets", alpha=[0, 200])]
    [['superfacets', 'alpha=0.0'], ['superfacets', 'alpha=200.0']]
    """
    m = get_method(method)
    names = sorted(values)
    lists = []
    for n in names:
        v = values[n]
        v = list(v) if isinstance(v, (list, tuple, np.ndarray)) else [v]
        if not v:
            raise ParameterError(f"no values given for {n}")
        lists.append(v)
    out = []
    for combo in product(*lists):
        p = m.resolve(dict(zip(names, combo)))
        out.append(Config(method, tuple(sorted(p.items()))))
    return list(dict.fromkeys(out))




def parse_params(items) -> dict[str, list[str]]:
    """``NAME=V1,V2`` options (``--param``) as ``{name: [values]}``.

    Raises
    ------
    ParameterError
        On an item that is not ``NAME=V1[,V2...]``.
    """
    out: dict[str, list[str]] = {}
    for item in items:
        name, sep, vals = item.partition("=")
        values = [v.strip() for v in vals.split(",") if v.strip()]
        if not sep or not name.strip() or not values:
            raise ParameterError(f"--param: expected NAME=V1,V2, got {item!r}")
        out[name.strip()] = values
    return out


def method_grid(methods: list[Method], values: dict[str, list]) -> dict[str, dict[str, list]]:
    """Share parameter values out to methods: ``{method name: {parameter: values}}``.

    A name ``NAME`` applies to each method that has that parameter;
    ``METHOD.NAME`` to that method only.

    Raises
    ------
    ParameterError
        If a name applies to none of ``methods`` (the message lists the
        parameters of each).
    """
    out: dict[str, dict[str, list]] = {m.name: {} for m in methods}
    for name, vals in values.items():
        scope, dot, pname = name.rpartition(".")
        hit = False
        for m in methods:
            if (not dot or scope == m.name) and pname in m.defaults:
                out[m.name][pname] = list(vals)
                hit = True
        if not hit:
            have = "; ".join(f"{m.name}: {', '.join(sorted(m.defaults)) or 'none'}"
                             for m in methods)
            raise ParameterError(f"--param {name}: no method given has it (parameters of "
                                 f"{have})")
    return out
