"""The length unit a scan file's coordinates are in, where the file says it.

A LAS or LAZ file names its coordinate reference system (GeoTIFF keys or WKT, read by
laspy's ``parse_crs`` through pyproj, the ``clouds`` extra); an E57 file's coordinates are
metres by the standard (ASTM E2807). Other formats say nothing: their sizes stay "in the
data's units".
"""

from __future__ import annotations

import warnings
from pathlib import Path

__all__ = ["length_unit", "geographic_note", "UNIT_SYMBOLS"]

#: The symbols of the commonest projected coordinate systems' units (pyproj's names); any
#: other unit is said by its name.
UNIT_SYMBOLS = {"metre": "m", "meter": "m", "kilometre": "km", "foot": "ft",
                "US survey foot": "US survey ft"}


def length_unit(path) -> str | None:
    """The horizontal length unit of a scan file's coordinates, where the file declares it.

    Parameters
    ----------
    path : str or os.PathLike
        A point cloud file.

    Returns
    -------
    str or None
        A symbol (:data:`UNIT_SYMBOLS`: ``'m'``, ``'ft'``, ``'US survey ft'``) or the unit's
        name: of a LAS/LAZ file's projected coordinate reference system (read with laspy
        and pyproj; None where either is missing, the file names no system or a
        geographic one, whose coordinates are angles), ``'m'`` of an E57 file; None for
        every other format.

    Raises
    ------
    None
        A file that cannot be read gives None: the readers say what is wrong with it.

    Examples
    --------
    >>> length_unit("scan.e57"), length_unit("scan.ply")
    ('m', None)
    """
    from .files import split_suffix

    path = Path(path)
    fmt, comp = split_suffix(path)
    if fmt == "e57" and not comp:
        return "m"
    return _crs_unit(_las_crs(path))


def geographic_note(path) -> str:
    """A note for a LAS/LAZ file whose coordinates are longitude and latitude: the method's
    distances would add degrees to heights in metres.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    str
        The note, or ``''`` where the file names a projected system, none, or cannot be
        read (as :func:`length_unit`).

    Raises
    ------
    None

    Examples
    --------
    >>> geographic_note("scan.ply")
    ''
    """
    crs = _horizontal(_las_crs(path))
    if crs is None or not crs.is_geographic:
        return ""
    return (f"{Path(path).name}: its coordinates are longitude and latitude ({crs.name}, "
            "degrees): the superpoints' distances add degrees to heights; reproject it to a "
            "projected system first (PDAL: filters.reprojection out_srs=EPSG:...)")


def _las_crs(path):
    """A LAS/LAZ file's pyproj CRS; None for another format, no laspy or pyproj, no CRS, or
    a file or CRS that cannot be read."""
    from .files import split_suffix

    fmt, comp = split_suffix(Path(path))
    if fmt not in ("las", "laz") or comp:
        return None
    try:
        import laspy
        import pyproj  # noqa: F401  (laspy's parse_crs needs it)

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            with laspy.open(str(path)) as reader:
                return reader.header.parse_crs()
    except Exception:  # (no laspy or pyproj, a malformed header or CRS)
        return None


def _crs_unit(crs) -> str | None:
    """The horizontal unit of a pyproj CRS (its first sub-system's where compound): a
    symbol or a name; None for no system, or a geographic one."""
    crs = _horizontal(crs)
    if crs is None or not crs.is_projected or not crs.axis_info:
        return None
    name = crs.axis_info[0].unit_name
    return UNIT_SYMBOLS.get(name, name) if name else None


def _horizontal(crs):
    """A pyproj CRS's horizontal system: a compound one's first (the vertical one follows);
    None for None."""
    if crs is not None and getattr(crs, "is_compound", False) and crs.sub_crs_list:
        return crs.sub_crs_list[0]
    return crs
