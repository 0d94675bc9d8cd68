"""Batch clipping of datasets on Dask Distributed: what ``rnsca batch`` runs.

A job lists its input files (`find_inputs`: GeoParquet, FlatGeobuf, GeoJSON text
sequences), cuts them into partitions (`plan`: runs of Parquet row groups, ranges of
FlatGeobuf features, byte ranges of a sequence's records), and clips each partition in a
task on a Dask worker (`run_partition`: read, `rnsca.dask.clip_frame`, write), which
writes it as one GeoParquet file of the output folder, named after the partition:
``<file number>-<partition number>-<file stem>.parquet``, so the files sort in input
order. Each file is written under a temporary name (a dot file, which dataset readers
skip) and renamed into place (``os.replace``, atomic on one file system): a file with a
partition's name is complete. That makes the job resumable: a partition whose file is
there and readable is not clipped again (`pending`), and a worker that dies mid-task
leaves at most a temporary file, removed at the next start, while its task runs again
elsewhere (Dask reschedules it).

With many windows (`Job.windows`, read from a file by `read_windows`), each row is
clipped to every window its geometry touches and gives a row per window, in input
order, then window order, with the window's index (its row in the file) in a column.

The output folder records the job (`MANIFEST`: window(s), options, encoding,
partitioning and input files); a second run into it must be the same job, so that no
stale partition of another one is left beside new ones. The input and output paths
must be the same on the client and on the workers (a shared file system, or the same
volume mounted in every container).

A partition that cannot be read or clipped fails alone, with a `PartitionError` naming
the file and, where known, the row (or the record of a text sequence); the others are
written, and the job reports every failure at the end.

Needs the ``dask`` extra (dask.distributed, geopandas, pyarrow, pyogrio).
"""

from __future__ import annotations

import csv
import glob
import hashlib
import json
import os
import re
import time
import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np
import shapely

from rnsca.dask import clip_frame, use_threads
from rnsca.errors import (
    InvalidGeometryError,
    InvalidOptionError,
    InvalidWindowError,
    RnscaError,
)
from rnsca.io.geojson_seq import Framing, framing_of_path, parse_record, split_records

__all__ = ["Encoding", "InputFormat", "Partition", "Job", "PartitionReport", "BatchReport",
           "PartitionError", "MANIFEST", "find_inputs", "plan", "pending", "run_partition",
           "run", "local_cluster", "threads_per_task", "read_windows"]

#: The job's record in the output folder (dataset readers skip names starting with ``_``).
MANIFEST = "_rnsca_batch.json"
#: File name endings read as GeoParquet and FlatGeobuf (compared case-insensitively);
#: GeoJSON text sequences are those `rnsca.io.geojson_seq.framing_of_path` knows.
PARQUET_SUFFIXES = (".parquet", ".geoparquet", ".pq")
FLATGEOBUF_SUFFIXES = (".fgb",)
_TEMPORARY = re.compile(r"^\..+\.[0-9a-f]{32}\.tmp$")
_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")
# GeoArrow holds one geometry type per column: lines and polygons are written as their
# multi kind (a clip may cut any of them in parts), so every partition has one schema.
_MULTI_OF = {"LineString": "MultiLineString", "MultiLineString": "MultiLineString",
             "Polygon": "MultiPolygon", "MultiPolygon": "MultiPolygon",
             "Point": "Point", "MultiPoint": "MultiPoint"}


class PartitionError(RnscaError):
    """A partition could not be read, clipped or written; the message names the file.

    Attributes
    ----------
    file : str
        The input file.
    row : int or None
        The row (feature) of the file at fault, where known.
    """

    def __init__(self, message: str, file: str = "", row: int | None = None) -> None:
        super().__init__(message, file, row)
        self.file, self.row = file, row

    def __str__(self) -> str:
        return str(self.args[0])


class Encoding(str, Enum):
    """How the output's geometry column is stored (GeoParquet 1.1)."""

    WKB = "wkb"
    """Well-known binary: any mix of geometry types; what every GeoParquet reader reads."""
    GEOARROW = "geoarrow"
    """GeoArrow native arrays (one type per column; lines and polygons as multi kinds)."""

    @classmethod
    def _missing_(cls, value: object) -> Encoding:
        raise InvalidOptionError(
            f"unknown encoding {value!r}; expected one of {', '.join(e.value for e in cls)}")


class InputFormat(str, Enum):
    """The kinds of input file."""

    PARQUET = "parquet"
    FLATGEOBUF = "flatgeobuf"
    GEOJSON_SEQ = "geojsonseq"


@dataclass(frozen=True)
class Partition:
    """A part of one input file, clipped by one task into one output file.

    Attributes
    ----------
    path : str
        The input file.
    format : InputFormat
    file_number, number : int
        The file's place among the inputs, and the partition's within the file.
    start, stop : int
        Its rows ``[start, stop)`` (Parquet, FlatGeobuf), or bytes (text sequences). For
        a file whose layout could not be read, ``0, -1``: the whole file (its task
        reports why it cannot be read).
    row_groups : tuple of int
        Parquet: the row groups it reads.
    framing : Framing or None
        Text sequences: how records are delimited.
    """

    path: str
    format: InputFormat
    file_number: int
    number: int
    start: int
    stop: int
    row_groups: tuple[int, ...] = ()
    framing: Framing | None = None

    @property
    def name(self) -> str:
        """Return the output file's name."""
        stem = _UNSAFE.sub("_", Path(self.path).stem) or "input"
        return f"{self.file_number:06d}-{self.number:06d}-{stem}.parquet"

    def where(self, position: int | None = None) -> str:
        """Return the input file, with the row at `position` in the partition if given."""
        if position is None:
            return self.path
        if self.format is InputFormat.GEOJSON_SEQ:
            return f"{self.path}: record {position} after byte {self.start}"
        return f"{self.path}: row {self.start + position}"


@dataclass(frozen=True)
class Job:
    """What a batch job does to each partition.

    Attributes
    ----------
    output : str
        The output folder.
    window : tuple of 4 float, or None
        The window; None with `windows`.
    windows : tuple of tuples of 4 float, or None
        Many windows instead of `window` (`read_windows`): each row gives a row per
        window its geometry meets, the window's index in `window_column`.
    window_column : str
        With `windows`: the output column of the window index (int64).
    options : dict
        `rnsca.clip`'s options (``method``, ``n``, ``mode``, ``boundary``, ...).
    keep_empty : bool
        Keep rows clipped to nothing, with an empty geometry (see `rnsca.dask.clip`).
    encoding : Encoding
    threads : int or None
        Threads of each task's kernels (Numba's, and pyarrow's pool); None leaves the
        worker's (Numba: ``NUMBA_NUM_THREADS``, read when Numba is first imported, which
        in a worker may be before a nanny's ``env`` is applied). `local_cluster`'s
        `threads_per_task` gives each worker its share of the cores. Not part of the
        job's identity: it changes no output.
    """

    output: str
    window: tuple[float, float, float, float] | None
    options: dict[str, Any] = field(default_factory=dict)
    keep_empty: bool = False
    encoding: Encoding = Encoding.WKB
    threads: int | None = None
    windows: tuple[tuple[float, float, float, float], ...] | None = None
    window_column: str = "window"

    def __post_init__(self) -> None:
        if (self.window is None) == (self.windows is None):
            raise InvalidWindowError("a job has one of window and windows")
        if self.windows is not None and self.keep_empty:
            raise InvalidOptionError(
                "keep_empty applies to one window: with many windows a row gives a row "
                "per window its geometry meets, and none for the others")

    def target(self, partition: Partition) -> str:
        """Return the path of `partition`'s output file."""
        return os.path.join(self.output, partition.name)


@dataclass(frozen=True)
class PartitionReport:
    """What one task did: rows read and written, and its time in seconds.

    ``seconds`` in all; ``read_s``, ``clip_s`` and ``write_s`` of its three steps.
    """

    name: str
    rows_in: int
    rows_out: int
    seconds: float
    read_s: float = 0.0
    clip_s: float = 0.0
    write_s: float = 0.0


@dataclass
class BatchReport:
    """A job's outcome.

    Attributes
    ----------
    partitions : int
        Partitions of the job.
    skipped : int
        Already written by an earlier run (not redone).
    written : list of PartitionReport
        Partitions written by this run, in the order they finished.
    failed : list of (Partition, str)
        Partitions that failed, with why.
    seconds : float
        Wall time of this run (the cluster's start excluded).
    """

    partitions: int
    skipped: int = 0
    written: list[PartitionReport] = field(default_factory=list)
    failed: list[tuple[Partition, str]] = field(default_factory=list)
    seconds: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """Return the report as JSON-ready values."""
        return {"partitions": self.partitions, "written": len(self.written),
                "skipped": self.skipped, "failed": len(self.failed),
                "rows_in": sum(r.rows_in for r in self.written),
                "rows_out": sum(r.rows_out for r in self.written),
                "seconds": round(self.seconds, 3),
                "errors": [message for _, message in self.failed]}


def input_format(path: str | Path) -> InputFormat | None:
    """Return the format of a file by its name, or None for another kind."""
    name = str(path).lower()
    if name.endswith(PARQUET_SUFFIXES):
        return InputFormat.PARQUET
    if name.endswith(FLATGEOBUF_SUFFIXES):
        return InputFormat.FLATGEOBUF
    if framing_of_path(name) is not None:
        return InputFormat.GEOJSON_SEQ
    return None


def find_inputs(spec: str) -> list[Path]:
    """Return the input files of `spec`: a file, a folder (searched through) or a glob.

    Files of a folder or glob are sorted by path; names starting with ``.`` or ``_``
    (hidden files, dataset metadata such as ``_metadata``) are left out, and so, in a
    folder, are files of other kinds.

    Raises
    ------
    InvalidOptionError
        Nothing matches, or a file named (or matched by the glob) is of another kind.
    """
    path = Path(spec)
    if path.is_file():
        files = [path]
    elif path.is_dir():
        files = sorted(p for p in path.rglob("*") if p.is_file()
                       and not any(part.startswith((".", "_"))
                                   for part in p.relative_to(path).parts)
                       and input_format(p) is not None)
    else:
        files = sorted(Path(p) for p in glob.glob(spec, recursive=True)
                       if Path(p).is_file() and not Path(p).name.startswith("_"))
    if not files:
        raise InvalidOptionError(f"{spec}: no such file, and no GeoParquet, FlatGeobuf or "
                                 "GeoJSON text sequence file found there")
    for file in files:
        if input_format(file) is None:
            raise InvalidOptionError(
                f"{file}: not an input rnsca batch reads (GeoParquet .parquet, FlatGeobuf "
                ".fgb, or a GeoJSON text sequence .geojsons, .geojsonl, .ndjson)")
    return files


def plan(files: Sequence[str | Path], *, rows_per_partition: int = 500_000,
         bytes_per_partition: int = 128 * 2**20) -> list[Partition]:
    """Return the partitions of `files`, in input order.

    A Parquet file is cut between row groups, about `rows_per_partition` rows each (a
    row group is never split: write big files with row groups of that size or smaller);
    a FlatGeobuf file into ranges of `rows_per_partition` features; a text sequence
    into ranges of about `bytes_per_partition` bytes, cut between records. Only layouts
    are read here (Parquet footers, FlatGeobuf headers, a few bytes of a sequence per
    cut); a file whose layout cannot be read is one partition, whose task fails naming it.
    """
    if rows_per_partition < 1 or bytes_per_partition < 1:
        raise InvalidOptionError("partition sizes must be at least 1")
    partitions: list[Partition] = []
    for number, file in enumerate(files):
        path = os.path.abspath(file)
        kind = input_format(path)
        if kind is None:
            raise InvalidOptionError(f"{file}: not GeoParquet, FlatGeobuf or a GeoJSON "
                                     "text sequence")
        try:
            if kind is InputFormat.PARQUET:
                partitions += _plan_parquet(path, number, rows_per_partition)
            elif kind is InputFormat.FLATGEOBUF:
                partitions += _plan_flatgeobuf(path, number, rows_per_partition)
            else:
                partitions += _plan_sequence(path, number, bytes_per_partition)
        except Exception:  # noqa: BLE001 - the layout is unreadable: its task says why
            partitions.append(Partition(path, kind, number, 0, 0, -1))
    return partitions


def _plan_parquet(path: str, number: int, rows: int) -> list[Partition]:
    import pyarrow.parquet as pq

    metadata = pq.read_metadata(path)
    out: list[Partition] = []
    groups: list[int] = []
    start = count = 0
    for group in range(metadata.num_row_groups):
        groups.append(group)
        count += metadata.row_group(group).num_rows
        if count >= rows or group == metadata.num_row_groups - 1:
            out.append(Partition(path, InputFormat.PARQUET, number, len(out), start,
                                 start + count, tuple(groups)))
            start, count, groups = start + count, 0, []
    return out or [Partition(path, InputFormat.PARQUET, number, 0, 0, 0, ())]


def _plan_flatgeobuf(path: str, number: int, rows: int) -> list[Partition]:
    import pyogrio

    total = int(pyogrio.read_info(path)["features"])
    starts = range(0, max(total, 1), rows)
    return [Partition(path, InputFormat.FLATGEOBUF, number, k, start,
                      min(start + rows, total)) for k, start in enumerate(starts)]


def _plan_sequence(path: str, number: int, size: int) -> list[Partition]:
    framing = framing_of_path(path)
    assert framing is not None
    total = os.path.getsize(path)
    # A cut goes just before an RS (RFC 8142), or just after a line feed (lines); a
    # record spanning a cut target goes to the partition it starts in.
    separator = b"\x1e" if framing is Framing.RS else b"\n"
    cuts = [0]
    with open(path, "rb") as stream:
        for target in range(size, total, size):
            if target <= cuts[-1]:
                continue
            stream.seek(target)
            found, offset = -1, target
            while found < 0:
                block = stream.read(1 << 16)
                if not block:
                    break
                found = block.find(separator)
                offset += len(block) if found < 0 else found
            if found < 0:
                break
            cut = offset if framing is Framing.RS else offset + 1
            if cuts[-1] < cut < total:
                cuts.append(cut)
    cuts.append(total)
    return [Partition(path, InputFormat.GEOJSON_SEQ, number, k, a, b, framing=framing)
            for k, (a, b) in enumerate(zip(cuts[:-1], cuts[1:], strict=True))]


def read_windows(path: str | Path) -> tuple[tuple[float, float, float, float], ...]:
    r"""Return the windows of a file, one ``(xmin, ymin, xmax, ymax)`` per row.

    Two formats, by the name's ending:

    - ``.json``: a JSON array of ``[xmin, ymin, xmax, ymax]`` arrays of numbers;
    - anything else (``.csv``, ``.txt``): CSV text, a window per line as four numbers
      ``xmin,ymin,xmax,ymax``; blank lines and lines starting with ``#`` are skipped, and
      a first line ``xmin,ymin,xmax,ymax`` is a header.

    A window's index (the output's window column) is its row among the windows, from 0
    (header, comments and blank lines not counted).

    Raises
    ------
    InvalidWindowError
        Naming the file and the line (CSV) or the element (JSON, from 0) at fault: not
        four numbers, not finite, ``min >= max``, or no window at all.
    InvalidOptionError
        The file cannot be read.

    Examples
    --------
    >>> import tempfile, os
    >>> with tempfile.NamedTemporaryFile("w", suffix=".csv", delete=False) as f:
    ...     _ = f.write("xmin,ymin,xmax,ymax\n0,0,10,10\n# a comment\n5,5,20,20\n")
    >>> read_windows(f.name)
    ((0.0, 0.0, 10.0, 10.0), (5.0, 5.0, 20.0, 20.0))
    >>> os.remove(f.name)
    """
    name = str(path)
    try:
        with open(path, encoding="utf-8") as stream:
            text = stream.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidOptionError(f"{name}: cannot read the windows file: {exc}") from None
    rows: list[tuple[str, Any]] = []   # (where, values)
    if name.lower().endswith(".json"):
        try:
            document = json.loads(text)
        except ValueError as exc:
            raise InvalidWindowError(f"{name}: not JSON: {exc}") from None
        if not isinstance(document, list):
            raise InvalidWindowError(f"{name}: expected a JSON array of [xmin, ymin, xmax, "
                                     f"ymax] arrays, got a {type(document).__name__}")
        rows = [(f"element {k}", item) for k, item in enumerate(document)]
    else:
        for number, fields in enumerate(csv.reader(text.splitlines()), start=1):
            if not fields or not "".join(fields).strip() or fields[0].lstrip().startswith("#"):
                continue
            if not rows and [f.strip().lower() for f in fields] == ["xmin", "ymin", "xmax",
                                                                     "ymax"]:
                continue
            rows.append((f"line {number}", fields))
    windows: list[tuple[float, float, float, float]] = []
    for where, values in rows:
        try:
            if isinstance(values, (str, bytes, dict)) or len(values) != 4 or any(
                    isinstance(v, bool) for v in values):
                raise ValueError
            xmin, ymin, xmax, ymax = (float(v) for v in values)
        except (TypeError, ValueError):
            raise InvalidWindowError(
                f"{name}: {where}: expected four numbers xmin, ymin, xmax, ymax, got "
                f"{values!r:.80}") from None
        window = (xmin, ymin, xmax, ymax)
        if not (np.isfinite(window).all() and xmin < xmax and ymin < ymax):
            raise InvalidWindowError(
                f"{name}: {where}: window {list(window)} must be finite with xmin < xmax "
                "and ymin < ymax")
        windows.append(window)
    if not windows:
        raise InvalidWindowError(f"{name}: no window in the file (a window per line: "
                                 "xmin,ymin,xmax,ymax)")
    return tuple(windows)


def is_complete(path: str) -> bool:
    """Return whether `path` is a readable GeoParquet file (a partition written whole)."""
    import pyarrow.parquet as pq

    try:
        metadata = pq.read_metadata(path).metadata
    except (OSError, ValueError):
        return False
    return metadata is not None and b"geo" in metadata


def pending(job: Job, partitions: Sequence[Partition]) -> list[Partition]:
    """Return the partitions whose output is not there yet, after preparing the folder.

    Creates the output folder, records the job in it (`MANIFEST`) or checks it is the
    job recorded there, and removes temporary files left by an interrupted run (run one
    job at a time into a folder).

    Raises
    ------
    InvalidOptionError
        The folder holds the output of another job.
    """
    os.makedirs(job.output, exist_ok=True)
    record = _manifest(job, partitions)
    manifest = os.path.join(job.output, MANIFEST)
    if os.path.exists(manifest):
        with open(manifest, encoding="utf-8") as stream:
            try:
                recorded = json.load(stream)
            except ValueError:
                recorded = None
        if recorded != record:
            differs = sorted(k for k in record if not isinstance(recorded, dict)
                             or recorded.get(k) != record[k])
            raise InvalidOptionError(
                f"{job.output} holds the output of another job (it differs in: "
                f"{', '.join(differs)}): give another OUTPUT, or empty this one")
    else:
        _write_atomically(manifest, json.dumps(record, indent=1).encode())
    _remove_temporary_files(job.output)
    return [p for p in partitions if not is_complete(job.target(p))]


def _remove_temporary_files(folder: str) -> None:
    """Remove what tasks that died while writing left (their partitions ran again)."""
    for entry in os.scandir(folder):
        if _TEMPORARY.match(entry.name):
            try:
                os.remove(entry.path)
            except FileNotFoundError:  # its writer finished meanwhile (a task run twice)
                pass


def _manifest(job: Job, partitions: Sequence[Partition]) -> dict[str, Any]:
    files = sorted({(p.file_number, p.path) for p in partitions})
    windows = None
    if job.windows is not None:
        table = np.asarray(job.windows, dtype=np.float64)
        windows = {"count": table.shape[0], "column": job.window_column,
                   "sha256": hashlib.sha256(table.tobytes()).hexdigest()}
    return {"window": None if job.window is None else list(job.window), "windows": windows,
            "options": {k: (v.value if isinstance(v, Enum) else v)
                        for k, v in sorted(job.options.items())},
            "keep_empty": job.keep_empty, "encoding": job.encoding.value,
            "inputs": [path for _, path in files],
            "partitions": [[p.file_number, p.number, p.start, p.stop] for p in partitions]}


def _write_atomically(path: str, data: bytes) -> None:
    temporary = _temporary_name(path)
    try:
        with open(temporary, "wb") as stream:
            stream.write(data)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def _temporary_name(path: str) -> str:
    folder, name = os.path.split(path)
    return os.path.join(folder, f".{name}.{uuid.uuid4().hex}.tmp")


def run_partition(partition: Partition, job: Job) -> PartitionReport:
    """Read, clip and write one partition (what each task runs); return what it did.

    Raises
    ------
    PartitionError
        Naming the file (and the row, where known) of input that cannot be read or
        clipped, or the output file that cannot be written.
    """
    started = time.perf_counter()
    if job.threads is not None:
        use_threads(job.threads)
    try:
        frame, keep_index = _read(partition)
    except PartitionError:
        raise
    except Exception as exc:  # noqa: BLE001 - any reader's failure, named and passed on
        rows = "" if partition.stop < 0 or partition.format is InputFormat.GEOJSON_SEQ \
            else f": rows {partition.start}-{partition.stop - 1}"
        raise PartitionError(f"{partition.path}{rows}: cannot read: "
                             f"{type(exc).__name__}: {exc}", partition.path) from None
    read = time.perf_counter()
    try:
        if job.windows is not None:
            clipped = clip_frame(frame, windows=np.asarray(job.windows, dtype=np.float64),
                                 window_column=job.window_column, **job.options)
        else:
            clipped = clip_frame(frame, job.window, keep_empty=job.keep_empty,
                                 **job.options)
    except InvalidGeometryError as exc:
        position = exc.geometry
        row = None if position is None or partition.format is InputFormat.GEOJSON_SEQ \
            else partition.start + position
        detail = exc.detail if exc.detail is not None and position is not None else f": {exc}"
        raise PartitionError(f"{partition.where(position)}{detail}", partition.path,
                             row) from None
    except RnscaError as exc:
        raise PartitionError(f"{partition.path}: {exc}", partition.path) from None
    clipped_at = time.perf_counter()
    target = job.target(partition)
    try:
        _write(clipped, target, job.encoding, keep_index, frame)
    except (OSError, ValueError, TypeError) as exc:
        raise PartitionError(f"{partition.path}: cannot write {target}: {exc}",
                             partition.path) from None
    done = time.perf_counter()
    return PartitionReport(partition.name, len(frame), len(clipped), done - started,
                           read - started, clipped_at - read, done - clipped_at)


def _read(partition: Partition) -> tuple[Any, bool]:
    """Return the partition as a GeoDataFrame, and whether its index is data to keep."""
    import pandas as pd

    if partition.format is InputFormat.PARQUET:
        frame = _read_parquet(partition)
    elif partition.format is InputFormat.FLATGEOBUF:
        import pyogrio

        if partition.stop < 0:
            frame = pyogrio.read_dataframe(partition.path)
        else:
            frame = pyogrio.read_dataframe(partition.path, skip_features=partition.start,
                                           max_features=partition.stop - partition.start)
    else:
        frame = _read_sequence(partition)
    return frame, not isinstance(frame.index, pd.RangeIndex)


def _read_parquet(partition: Partition) -> Any:
    import pyarrow.parquet as pq
    from geopandas.io.arrow import _arrow_to_geopandas

    file = pq.ParquetFile(partition.path)
    table = file.read() if partition.stop < 0 else file.read_row_groups(
        list(partition.row_groups))
    metadata = table.schema.metadata or {}
    if b"geo" not in metadata:
        raise PartitionError(f"{partition.path}: not GeoParquet (no 'geo' metadata)",
                             partition.path)
    geo = json.loads(metadata[b"geo"])
    # A bounding-box covering column (GeoParquet 1.1) would be stale once clipped; the
    # writer makes a new one.
    covering = [spec["bbox"]["xmin"][0] for spec in geo.get("columns", {}).values()
                if "bbox" in spec.get("covering", {})]
    if covering:
        table = table.drop_columns([c for c in covering if c in table.column_names])
    # geopandas' reader of an Arrow table with GeoParquet metadata (what read_parquet
    # runs on a whole file); a partition is a table of some row groups.
    return _arrow_to_geopandas(table)


def _read_sequence(partition: Partition) -> Any:
    import geopandas
    import orjson
    import pandas as pd

    with open(partition.path, "rb") as stream:
        stream.seek(partition.start)
        data = stream.read() if partition.stop < 0 else stream.read(
            partition.stop - partition.start)
    texts: list[str | None] = []
    properties: list[dict[str, Any]] = []
    ids: list[Any] = []
    for number, record_text in enumerate(split_records([data], partition.framing)):
        record = parse_record(record_text, number)
        kind = record.get("type") if isinstance(record, dict) else None
        if kind == "Feature":
            geometry = record.get("geometry")
            properties.append(record.get("properties") or {})
            ids.append(record.get("id"))
        elif kind in ("Point", "MultiPoint", "LineString", "MultiLineString", "Polygon",
                      "MultiPolygon", "GeometryCollection"):
            geometry = record
            properties.append({})
            ids.append(None)
        else:
            raise PartitionError(
                f"{partition.where(number)}: expected a GeoJSON Feature or Geometry, got "
                f"{kind if kind else type(record).__name__}", partition.path)
        texts.append(None if geometry is None else orjson.dumps(geometry).decode())
    values = np.asarray(texts, dtype=object)
    try:
        geometries = shapely.from_geojson(values)
    except shapely.errors.GEOSException:
        for number, geometry_text in enumerate(texts):  # find the record at fault
            try:
                shapely.from_geojson(geometry_text)
            except shapely.errors.GEOSException as exc:
                raise PartitionError(f"{partition.where(number)}: invalid geometry: {exc}",
                                     partition.path) from None
        raise
    columns = pd.DataFrame.from_records(properties, index=pd.RangeIndex(len(texts)))
    if any(i is not None for i in ids):
        columns.insert(0, "id", ids)
    return geopandas.GeoDataFrame(columns, geometry=geometries, crs="OGC:CRS84")


def _write(frame: Any, target: str, encoding: Encoding, keep_index: bool,
           source: Any) -> None:
    """Write `frame` to `target` atomically: a temporary file renamed into place."""
    temporary = _temporary_name(target)
    try:
        geoarrow = encoding is Encoding.GEOARROW
        if geoarrow:
            frame = _one_kind(frame, source)
        if geoarrow and (len(frame) == 0 or frame.geometry.isna().all()):
            _write_empty_geoarrow(frame, temporary, keep_index, _kind_of(source))
        else:
            frame.to_parquet(temporary, index=keep_index, schema_version="1.1.0",
                             geometry_encoding="geoarrow" if geoarrow else "WKB",
                             write_covering_bbox=True)
        os.replace(temporary, target)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def _kind_of(source: Any) -> str | None:
    """Return the one GeoArrow kind for the input's geometries, or None if it has none.

    Raises
    ------
    ValueError
        For geometries of several families (points, lines, polygons), or collections.
    """
    types = set(source.geometry.dropna().geom_type.unique()) if len(source) else set()
    kinds = {_MULTI_OF.get(t, t) for t in types}
    if "Point" in kinds and "MultiPoint" in kinds:
        kinds.discard("Point")
    if len(kinds) > 1 or kinds - set(_MULTI_OF.values()):
        raise ValueError(f"GeoArrow holds one geometry type per column; this input has "
                         f"{', '.join(sorted(types))}: use --encoding wkb")
    return kinds.pop() if kinds else None


def _one_kind(frame: Any, source: Any) -> Any:
    """Return `frame` with its geometries as the input's one GeoArrow kind (`_kind_of`)."""
    kind = _kind_of(source)
    if kind not in ("MultiLineString", "MultiPolygon", "MultiPoint"):
        return frame
    values = np.asarray(frame.geometry.array, dtype=object)
    out = np.full(len(values), shapely.from_wkt(f"{kind.upper()} EMPTY"), dtype=object)
    out[shapely.is_missing(values)] = None
    parts, index = shapely.get_parts(values, return_index=True)
    solid = ~shapely.is_empty(parts)
    make = {"MultiLineString": shapely.multilinestrings, "MultiPolygon": shapely.multipolygons,
            "MultiPoint": shapely.multipoints}[kind]
    if solid.any():
        make(parts[solid], indices=index[solid], out=out)
    frame = frame.copy()
    frame[frame.geometry.name] = frame.geometry.__class__(out, index=frame.index,
                                                          crs=frame.crs)
    return frame


def _write_empty_geoarrow(frame: Any, path: str, keep_index: bool, kind: str | None) -> None:
    """Write a frame without geometries with its column as GeoArrow `kind`.

    geopandas cannot convert an empty (or all-missing) column to GeoArrow, as the type
    comes from the values: the file is written as WKB, then its geometry field replaced
    by an empty (or all-null) one of `kind`'s type, from a one-row file of that kind.
    With no kind known (the input had no geometry either), it stays WKB.
    """
    import io

    import geopandas
    import pyarrow as pa
    import pyarrow.parquet as pq

    name = frame.geometry.name
    written = io.BytesIO()
    frame.to_parquet(written, index=keep_index, schema_version="1.1.0",
                     geometry_encoding="WKB", write_covering_bbox=True)
    if kind is None:
        with open(path, "wb") as stream:
            stream.write(written.getvalue())
        return
    written.seek(0)
    table = pq.read_table(written)
    model = io.BytesIO()
    geopandas.GeoDataFrame(
        geometry=[shapely.from_wkt(f"{kind.upper()} EMPTY")], crs=frame.crs,
    ).to_parquet(model, index=False, geometry_encoding="geoarrow")
    model.seek(0)
    model_field = pq.read_schema(model).field("geometry").with_name(name)
    column = pa.nulls(len(table), type=model_field.type)
    position = table.schema.get_field_index(name)
    table = table.set_column(position, model_field, column)
    geo = json.loads(table.schema.metadata[b"geo"])
    geo["columns"][name].update(encoding=kind.lower(), geometry_types=[kind])
    geo["columns"][name].pop("bbox", None)
    table = table.replace_schema_metadata({**table.schema.metadata,
                                           b"geo": json.dumps(geo).encode()})
    pq.write_table(table, path)


def run(job: Job, partitions: Sequence[Partition], client: Any, *,
        on_done: Callable[[Partition, PartitionReport | None, str | None], None] | None
        = None) -> BatchReport:
    """Run the job's pending partitions on a Dask `client`; return the report.

    Partitions already written are skipped (`pending`); the others run one task each
    (worker deaths are retried by Dask: ``distributed.scheduler.allowed-failures``).
    `on_done` is called in this process as each task ends, with its report or its error
    message.
    """
    from distributed import as_completed

    started = time.perf_counter()
    todo = pending(job, partitions)
    report = BatchReport(len(partitions), skipped=len(partitions) - len(todo))
    # Keys of this run only: a key of a cancelled run may linger on the scheduler.
    token = uuid.uuid4().hex[:12]
    futures = client.map(run_partition, todo, job=job,
                         key=[f"rnsca-batch-{p.name}-{token}" for p in todo])
    of_key = {f.key: p for f, p in zip(futures, todo, strict=True)}
    try:
        for future in as_completed(futures):
            partition = of_key[future.key]
            if future.status == "error":
                error = future.exception()
                message = str(error) if isinstance(error, PartitionError) else \
                    f"{partition.path}: {type(error).__name__}: {error}"
                report.failed.append((partition, message))
                if on_done is not None:
                    on_done(partition, None, message)
            else:
                done: PartitionReport = future.result()
                report.written.append(done)
                if on_done is not None:
                    on_done(partition, done, None)
            future.release()
    finally:
        client.cancel([f for f in futures if not f.done()])
    _remove_temporary_files(job.output)
    report.seconds = time.perf_counter() - started
    return report


def local_cluster(workers: int | None = None, *, dashboard_address: str | None = ":8787",
                  **kwargs: Any) -> Any:
    """Return a ``distributed.LocalCluster`` of worker processes on loopback.

    One process per core by default, one task thread each, and each process's share of
    the cores (`threads_per_task`) in its environment (``NUMBA_NUM_THREADS``,
    ``OMP_NUM_THREADS``, which Dask's nannies otherwise set to 1); give the same share to
    the job (`Job.threads`), since a worker may have imported Numba before its
    environment was set.
    """
    from distributed import LocalCluster

    workers = workers or os.cpu_count() or 1
    share = str(threads_per_task(workers))
    env = {"NUMBA_NUM_THREADS": share, "OMP_NUM_THREADS": share}
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                        host="127.0.0.1", dashboard_address=dashboard_address,
                        env=env, **kwargs)



def threads_per_task(workers: int) -> int:
    """Return each of `workers` single-threaded worker processes' share of this machine."""
    return max(1, (os.cpu_count() or 1) // max(1, workers))
