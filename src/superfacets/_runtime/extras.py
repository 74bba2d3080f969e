"""Optional dependencies: import one, or say which extra to install.

The core (segmenting, evaluating, writing labels, meshes and HTML pages)
needs numpy, scipy, trimesh, tqdm and plyfile (and the compiled kernels, built at
install). The rest comes with extras:

- ``render``: pictures and the viewer window (pyvista, Pillow);
- ``report``: result tables and figures (pandas, matplotlib);
- ``distributed``: ``batch`` and ``experiment`` on several processes or machines
  (dask.distributed; pyarrow for the Parquet manifest);
- ``all``: every extra; ``test``: the test suite's needs.

The baselines (normalized cuts, VSA) need only the core.
"""

from __future__ import annotations

import importlib

from ..errors import MissingExtraError

__all__ = ["require", "EXTRAS"]

#: Module -> the extra that installs it.
EXTRAS = {"pyvista": "render", "PIL": "render", "pandas": "report", "matplotlib": "report",
          "pypcd4": "clouds", "laspy": "clouds", "pye57": "clouds",
          "distributed": "distributed", "dask": "distributed", "pyarrow": "distributed",
          "networkx": "graph", "cut_pursuit_py": "baselines", "pgeof": "baselines",
          "sklearn": "baselines", "meshio": "volumes", "torch": "pyg",
          "torch_geometric": "pyg"}


def require(module: str, feature: str):
    """Import ``module``, or raise :class:`MissingExtraError` naming the extra.

    Parameters
    ----------
    module : str
        Top-level module name (``"pyvista"``, ``"pandas"``, ...).
    feature : str
        What needs it, for the message (``"render"``, ``"superfacets report"``).

    Returns
    -------
    module

    Raises
    ------
    MissingExtraError
        With the ``pip install 'superfacets[EXTRA]'`` command to run.

    Examples
    --------
    >>> np = require("numpy", "anything")
    """
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        extra = EXTRAS.get(module.split(".")[0], "all")
        raise MissingExtraError(
            f"{feature} needs {module.split('.')[0]}, which is not installed ({exc}); "
            f"install it with: pip install 'superfacets[{extra}]'") from None
