"""The collections of geometries `Client.clip` takes, taken apart and put back in kind.

A collection is a GeoPandas ``GeoDataFrame`` or ``GeoSeries``, a NumPy array or a list
(or tuple) of Shapely geometries, or a pyarrow ``Table`` or ``RecordBatch`` with a
GeoArrow geometry column. `collection_of` wraps one; its `rebuild` returns the same kind
holding only the rows given (by position), with their clipped geometries: the other
columns, the index labels, the names and the CRS as they were.

GeoPandas, pandas, NumPy, Shapely and pyarrow are imported only for a collection of
theirs (a ``GeoDataFrame`` can only exist once GeoPandas is loaded).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Any

from rnsca_client.errors import InvalidInputError
from rnsca_client.inputs import is_numpy_array

__all__ = ["Collection", "GeometryCollection", "TableCollection", "collection_of",
           "is_collection"]


@dataclass(frozen=True)
class Collection:
    """A caller's collection: its length, and how to put a clipped one back together."""

    data: Any

    def __len__(self) -> int:
        return len(self.data)


@dataclass(frozen=True)
class GeometryCollection(Collection):
    """Shapely geometries (an array, a list, a ``GeoSeries`` or a ``GeoDataFrame``'s).

    `geometries` is an object array of Shapely geometries or None; `column` names the
    clipped geometry column of a ``GeoDataFrame``.
    """

    geometries: Any = None
    column: str | None = None

    def rebuild(self, rows: Any, geometries: Any) -> Any:
        """Return the collection's kind holding `rows` (positions) with `geometries`."""
        data = self.data
        if _is_geopandas(data, "GeoDataFrame"):
            import geopandas

            out = data.take(rows)
            out[self.column] = geopandas.GeoSeries(geometries, index=out.index,
                                                   crs=data[self.column].crs)
            return out
        if _is_geopandas(data, "GeoSeries"):
            import geopandas

            return geopandas.GeoSeries(geometries, index=data.index.take(rows),
                                       crs=data.crs, name=data.name)
        if is_numpy_array(data):
            return geometries
        return type(data)(geometries.tolist()) if isinstance(data, tuple) \
            else geometries.tolist()


@dataclass(frozen=True)
class TableCollection(Collection):
    """A pyarrow ``Table`` or ``RecordBatch`` and the index of its geometry column."""

    table: Any = None
    index: int = 0

    def rebuild(self, rows: Any, column: Any, field: Any) -> Any:
        """Return the table's kind holding `rows` (positions), its geometry `column`."""
        import pyarrow as pa

        out = self.table.take(pa.array(rows, pa.int64())).set_column(self.index, field,
                                                                     column)
        if isinstance(self.data, pa.RecordBatch):
            return out.combine_chunks().to_batches()[0] if out.num_rows else \
                pa.RecordBatch.from_pylist([], schema=out.schema)
        return out


def _is_geopandas(data: Any, name: str) -> bool:
    module = sys.modules.get("geopandas")
    return module is not None and isinstance(data, getattr(module, name))


def is_collection(data: Any) -> bool:
    """Return whether `data` is a collection `collection_of` takes (without checking it).

    A list or tuple is one when its first item is a Shapely geometry (or None), so that
    a list of GeoJSON documents or of frames is not.
    """
    if _is_geopandas(data, "GeoDataFrame") or _is_geopandas(data, "GeoSeries"):
        return True
    module = type(data).__module__.split(".")[0]
    if module == "pyarrow":
        return type(data).__name__ in ("Table", "RecordBatch")
    if is_numpy_array(data):
        return True
    if isinstance(data, (list, tuple)):
        return not data or data[0] is None or type(data[0]).__module__.startswith("shapely")
    return False


def collection_of(data: Any, column: str | None = None) -> GeometryCollection | TableCollection:
    """Return `data` as a collection, its geometries checked.

    Parameters
    ----------
    data : GeoDataFrame, GeoSeries, ndarray, list, tuple, pyarrow.Table or RecordBatch
        The geometries (None: a missing one). A ``GeoDataFrame``'s active geometry column
        is clipped unless `column` names another; a table's is its one column tagged
        ``geoarrow.*`` (or a binary column named ``geometry``) unless `column` names it.
    column : str, optional
        The geometry column of a frame or table.

    Raises
    ------
    InvalidInputError
        `data` is none of those, or holds something that is not a Shapely geometry.
    """
    if _is_geopandas(data, "GeoDataFrame"):
        name = column if column is not None else data.geometry.name
        if name not in data.columns or not _is_geopandas(data[name], "GeoSeries"):
            raise InvalidInputError(f"no geometry column {name!r}; the frame's columns are "
                                    f"{list(data.columns)}")
        return GeometryCollection(data, data[name].to_numpy(), name)
    _refuse_column(data, column)
    if _is_geopandas(data, "GeoSeries"):
        return GeometryCollection(data, data.to_numpy())
    if type(data).__module__.split(".")[0] == "pyarrow" and type(data).__name__ in (
            "Table", "RecordBatch"):
        import pyarrow as pa

        from rnsca_client.geoarrow import find_geometry_column

        table = data if isinstance(data, pa.Table) else pa.Table.from_batches([data])
        return TableCollection(data, table, find_geometry_column(table.schema, column))
    if is_numpy_array(data) or isinstance(data, (list, tuple)):
        return GeometryCollection(data, _geometry_array(data))
    raise InvalidInputError(
        "clip takes a GeoDataFrame, a GeoSeries, an array or list of Shapely geometries, "
        f"or a pyarrow Table or RecordBatch with a GeoArrow column, not "
        f"{type(data).__name__} (GeoJSON documents go to clip_geojson)")


def _refuse_column(data: Any, column: str | None) -> None:
    if column is not None and not (type(data).__module__.split(".")[0] == "pyarrow"):
        raise InvalidInputError(f"column= names a frame's or a table's geometry column; "
                                f"a {type(data).__name__} has none")


def _geometry_array(data: Any) -> Any:
    """Return an array or list of geometries as a 1-D object array, each one checked."""
    try:
        import numpy as np
        import shapely
    except ImportError:
        raise ImportError("Shapely and NumPy are needed for collections of geometries: "
                          "pip install 'rnsca-client[shapely]'") from None
    if is_numpy_array(data) and data.ndim != 1:
        raise InvalidInputError(f"an array of geometries must be 1-D, got shape {data.shape}")
    geometries = np.empty(len(data), dtype=object)
    geometries[:] = list(data)
    bad = ~(shapely.is_geometry(geometries) | shapely.is_missing(geometries))
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise InvalidInputError(f"item {first} is not a Shapely geometry (nor None): "
                                f"{type(geometries[first]).__name__}")
    return geometries
