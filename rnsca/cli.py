"""The ``rnsca`` command line.

Commands: ``clip`` (GeoJSON or SVG documents, GeoJSON text sequences), ``batch``
(datasets of GeoParquet, FlatGeobuf or text sequences, on Dask; needs the ``dask``
extra), ``glyphs`` (text from a font file, as SVG; needs the ``fonts`` extra),
``segments`` (.npy arrays of segments), ``tiles`` (a vector tile pyramid as PMTiles or
z/x/y.mvt; needs the ``tiles`` extra), ``backends``, ``warm-up`` and ``serve`` (the HTTP
service; needs the ``service`` extra).
Errors print one line, ``error: <what and where>``, on stderr and exit with 2 for a wrong
command line (options, window, the kind of input) or 1 for input that cannot be clipped
(not JSON, invalid GeoJSON or SVG, unreadable files).
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import re
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, BinaryIO, NoReturn

import numpy as np
import typer

import rnsca
from rnsca.backends.base import Operation
from rnsca.backends.registry import (
    available_backends,
    configure_opencl,
    get_backend,
    opencl_report,
)
from rnsca.clip_svgdoc import clip_svg_document
from rnsca.errors import (
    BackendUnavailableError,
    InvalidOptionError,
    InvalidWindowError,
    RnscaError,
)
from rnsca.fonts import clip_glyphs
from rnsca.io.geojson import dumps, loads
from rnsca.io.geojson_seq import RS, Framing, framing_of_path, split_records, write_records
from rnsca.io.svgpath import warm_up_readers
from rnsca.options import Backend, Boundary, Mode
from rnsca.runtime import collector_paused, configure_process

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID

__all__ = ["app", "PROGRESS_MIN_BYTES"]

#: Exit status for input that cannot be clipped.
EXIT_DATA = 1
#: Exit status for a wrong command line (as Typer uses for its own usage errors).
EXIT_USAGE = 2
#: File name endings read as GeoJSON (compared case-insensitively).
GEOJSON_SUFFIXES = (".geojson", ".json")
#: File name endings read as GeoJSON text sequences, clipped as they are read
#: (`rnsca.io.geojson_seq.framing_of_path`).
SEQUENCE_SUFFIXES = (".geojsons", ".geojsonseq", ".geojsonl", ".geojsonld", ".ndjson",
                     ".jsonl")
#: File name endings read as SVG; so is input whose first character is ``<``.
SVG_SUFFIXES = (".svg",)
#: With stderr on a terminal, inputs of at least this many bytes get a progress bar.
PROGRESS_MIN_BYTES = 8 * 2**20
# Files are read and written in blocks of this size, so that the bar moves.
_BLOCK = 2**20
# Errors that mean the command line, not the input, is wrong.
_USAGE_ERRORS = (InvalidOptionError, InvalidWindowError, BackendUnavailableError)
# The first byte that is not JSON whitespace.
_NON_SPACE = re.compile(rb"[^ \t\r\n]")

app = typer.Typer(help="Clip geometry against a rectangular window.", no_args_is_help=True)


@app.callback()
def main(
    opencl_device: Annotated[str | None, typer.Option(
        envvar="RNSCA_OPENCL_DEVICE", help="OpenCL device for --backend opencl: "
        "'platform:device' (see `rnsca backends`) or part of its name [default: the first "
        "GPU, else the first device]")] = None,
    opencl_precision: Annotated[str, typer.Option(
        envvar="RNSCA_OPENCL_PRECISION", help="auto (float64 where the device has it, "
        "else float32), float64 or float32")] = "auto",
) -> None:
    """Clip geometry against a rectangular window."""
    configure_process()  # the CLI owns its process (see rnsca.runtime)
    try:
        configure_opencl(opencl_device, opencl_precision)
    except InvalidOptionError as exc:
        _fail(str(exc), EXIT_USAGE)


@app.command()
def backends() -> None:
    """List the backends that can run here, and the OpenCL devices found.

    One backend per line on stdout, with what it runs (its capabilities); each OpenCL
    device indented below ``opencl`` (``*`` marks the one selected). Why OpenCL is
    unavailable goes to stderr.
    """
    present = available_backends()
    for kind in present:
        capabilities = get_backend(kind).capabilities
        runs = ", ".join(o.value for o in Operation if o in capabilities.operations)
        typer.echo(f"{kind.value}: {runs} ({capabilities.precision.value})")
    report = opencl_report()
    if Backend.OPENCL not in present:
        typer.echo(f"opencl is not available: {report['reason']}", err=True)
    for device in report["devices"]:
        mark = "*" if device["id"] == report["selected"] else " "
        precision = f", {report['precision']}" if mark == "*" else ""
        typer.echo(f" {mark}{device['id']} {device['platform']} / {device['device']} "
                   f"({device['type']}, {'fp64' if device['fp64'] else 'no fp64'}{precision})")


@app.command()
def warm_up() -> None:
    """Compile the kernels into the on-disk cache (later processes load them)."""
    for kind in available_backends():
        get_backend(kind).warm_up()
    warm_up_readers()
    typer.echo("kernels ready")


@app.command()
def serve(
    host: Annotated[str | None, typer.Option(help="address to listen on [default: "
                                                  "RNSCA_HOST or 127.0.0.1]")] = None,
    port: Annotated[int | None, typer.Option(help="TCP port [default: RNSCA_PORT or "
                                                  "8000]")] = None,
    workers: Annotated[int | None, typer.Option(help="worker processes [default: "
                                                     "RNSCA_WORKERS or 1]")] = None,
) -> None:
    """Run the HTTP service under uvicorn (other settings from RNSCA_* variables)."""
    import os

    try:
        from service.config import Settings
        from service.serve import serve as run
    except ImportError as exc:
        _fail(f"the service needs the service extra: pip install 'rnsca[service]' ({exc})",
              EXIT_USAGE)
    for name, value in (("HOST", host), ("PORT", port), ("WORKERS", workers)):
        if value is not None:  # the workers build their app from the environment
            os.environ[f"RNSCA_{name}"] = str(value)
    try:
        settings = Settings()
    except ValueError as exc:
        _fail(f"invalid settings: {exc}", EXIT_USAGE)
    run(settings)


@app.command()
def segments(
    source: Annotated[Path, typer.Argument(help=".npy file of float (n, 4) segments")],
    output: Annotated[Path, typer.Argument(help=".npz file to write: segments, source, t")],
    window: Annotated[tuple[float, float, float, float],
                      typer.Option(help="xmin ymin xmax ymax")],
    method: Annotated[str, typer.Option(help="rnsca, cohen_sutherland, liang_barsky, "
                                             "nicholl_lee_nicholl or midpoint")] = "rnsca",
    n: Annotated[str, typer.Option(help="pieces per split, 2..64 or auto")] = "auto",
    max_depth: Annotated[int | None, typer.Option(help="0..32")] = None,
    tolerance: Annotated[float | None, typer.Option(help="leaf length")] = None,
    resolution: Annotated[str | None, typer.Option(help=_RESOLUTION_HELP)] = None,
    mode: Annotated[str, typer.Option(help="exact or approx")] = "exact",
    backend: Annotated[str, typer.Option(help="numba, numpy or opencl")] = "numba",
    verify: Annotated[bool, typer.Option(help="compare with Shapely")] = False,
) -> None:
    """Clip the segments of a .npy file and print the statistics as JSON."""
    try:
        data = np.load(source, allow_pickle=False)
        result = rnsca.clip_segments(
            data, window, method=method, n=int(n) if n.isdigit() else n,
            max_depth=max_depth, tolerance=tolerance, mode=mode, backend=backend,
            resolution=_resolution(resolution))
    except (RnscaError, ValueError, OSError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    np.savez(output, segments=result.segments, source=result.source, t=result.t)
    report = {"stats": result.stats.to_dict(), "method": result.method.value,
              "mode": result.mode.value, "backend": result.backend.value}
    if verify:
        report["verification"] = rnsca.verify(data, result, window).to_dict()
    typer.echo(json.dumps(report, indent=2))


@app.command()
def clip(
    source: Annotated[str | None, typer.Argument(
        metavar="INPUT", show_default=False,
        help="GeoJSON (.geojson or .json) or SVG (.svg) file; - or nothing reads "
             "stdin")] = None,
    # Required: Typer reads the Ellipsis so (a default must follow `source`'s).
    window: Annotated[str, typer.Option(
        "--window", "-w", show_default=False,
        help="xmin,ymin,xmax,ymax, e.g. 0,0,10,10 or -10,-10,10,10")] = ...,  # type: ignore[assignment]
    output: Annotated[str | None, typer.Option(
        "--output", "-o", show_default=False,
        help="file to write the clipped document to; default (or -): stdout")] = None,
    stats: Annotated[Path | None, typer.Option(
        "--stats", show_default=False,
        help="write the statistics (and verification) JSON to this file instead of "
             "stderr")] = None,
    verify: Annotated[bool, typer.Option(
        help="compare the clip with Shapely's intersection; exit 1 if it fails")] = False,
    method: Annotated[str, typer.Option(help="rnsca, cohen_sutherland, liang_barsky, "
                                             "nicholl_lee_nicholl or midpoint")] = "rnsca",
    n: Annotated[str, typer.Option(help="pieces (runs) per split, 2..64 or auto")] = "auto",
    max_depth: Annotated[int | None, typer.Option(help="0..32")] = None,
    tolerance: Annotated[float | None, typer.Option(
        help="leaf length; SVG: also how far flattened curves may stray")] = None,
    resolution: Annotated[str | None, typer.Option(help=_RESOLUTION_HELP)] = None,
    mode: Annotated[str, typer.Option(help="exact or approx (lines and points only)")] = "exact",
    backend: Annotated[str, typer.Option(help="numba or opencl")] = "numba",
    boundary: Annotated[str, typer.Option(
        help="closed keeps parts on the window's edge (as shapely.intersection); interior "
             "drops them (as shapely.clip_by_rect)")] = "closed",
    keep_empty: Annotated[bool, typer.Option(
        help="keep features left empty (with empty coordinates) instead of dropping them")
    ] = False,
    check_validity: Annotated[bool, typer.Option(
        help="count invalid input polygons in the stats with GEOS (costs more than the "
             "clip; invalid polygons are clipped ring by ring either way)")] = False,
    approx_bound: Annotated[float | None, typer.Option(
        help="with --verify --mode approx: the largest deviation to accept")] = None,
    indent: Annotated[bool, typer.Option(help="indent the output JSON by 2 spaces")] = False,
    progress: Annotated[bool | None, typer.Option(
        "--progress/--no-progress", show_default=False,
        help="show a progress bar on stderr (default: for inputs of 8 MiB or more when "
             "stderr is a terminal)")] = None,
    curves: Annotated[str, typer.Option(
        help="SVG: preserve (Béziers cut at the edges) or flatten (lines)")] = "preserve",
    fill: Annotated[str, typer.Option(
        help="SVG: auto (each shape as a fill if its fill is not none, else as a stroke), "
             "stroke or fill")] = "auto",
    fill_output: Annotated[str, typer.Option(
        help="SVG fills: clean (subpaths that are simple rings, joined along the window's "
             "edges) or raw (each subpath clamped onto the edges: faster, paints the "
             "same)")] = "clean",
    precision: Annotated[int | None, typer.Option(
        help="SVG: significant digits of the written path data [default: exact]")] = None,
    framing: Annotated[str | None, typer.Option(
        "--seq", show_default=False,
        help="read a GeoJSON text sequence, clipped a chunk of records at a time and "
             "written as it goes: rs (RFC 8142, records after RS) or lines (one per "
             "line); default: by the file's name (.geojsons: rs; .geojsonl, .ndjson, "
             ".jsonl: lines), or rs for stdin that starts with RS")] = None,
) -> None:
    """Clip a GeoJSON document to a window and write the clipped GeoJSON.

    Geometry, Feature and FeatureCollection documents are accepted; properties, ids and
    foreign members are kept, bbox members recomputed. The statistics go to stderr as
    JSON (or to --stats FILE), with the comparison with Shapely under --verify.

    SVG documents (a .svg file, or input starting with <) have every drawn shape
    clipped (basic shapes become paths, transforms applied) and the rest left intact;
    --keep-empty keeps emptied shapes as empty paths.

    GeoJSON text sequences (a .geojsons, .geojsonl or .ndjson file, or --seq) are read,
    clipped and written a chunk of records at a time, in the input's framing, so a
    sequence of any length takes the memory of one chunk; records left empty are
    dropped (unless --keep-empty). A bad record stops the command (exit 1) after the
    records before it are written.
    """
    bounds = _window_bounds(window)
    options: dict[str, Any] = dict(
        boundary=boundary, method=method, n=int(n) if n.isdigit() else n, max_depth=max_depth,
        tolerance=tolerance, mode=mode, backend=backend, check_validity=check_validity)
    with _reporting(EXIT_USAGE):
        if resolution is not None:
            options["resolution"] = _resolution(resolution)
        _check_options(bounds, options)
        if verify and Mode(mode) is Mode.APPROX and approx_bound is None:
            raise InvalidOptionError(
                "--verify with --mode approx needs --approx-bound (the largest deviation "
                "to accept)")
        clip_svg_document("<svg/>", bounds, curves=curves, fill_mode=fill,
                          fill_output=fill_output, precision=precision)  # checks them
    name, path = _input(source)
    with _reporting(EXIT_USAGE):
        chosen = None if framing is None else Framing(framing)
    sequence, pieces, prefix = _sequence_blocks(path, chosen)
    if sequence is not None:
        with _reporting(EXIT_USAGE):
            for flag, given in {"--verify": verify, "--indent": indent,
                                "--approx-bound": approx_bound is not None}.items():
                if given:
                    raise InvalidOptionError(f"{flag} does not apply to GeoJSON text "
                                             "sequences")
        report = _clip_sequence(pieces, sequence, bounds, options, keep_empty, output)
        with _reporting(EXIT_DATA):
            _write_report(report, stats)
        return
    bar = _ProgressBar(progress)
    try:
        with _reporting(EXIT_DATA):
            data = _read(path, bar, prefix)
            bar.phase(f"clipping {name}")
            if _is_svg(path, data):
                geojson_only = {"--verify": verify, "--check-validity": check_validity,
                                "--boundary": Boundary(boundary) is not Boundary.CLOSED,
                                "--approx-bound": approx_bound is not None,
                                "--indent": indent}
                text, report = _clip_svg(data, bounds, options, geojson_only,
                                         curves=curves, fill_mode=fill,
                                         fill_output=fill_output,
                                         precision=precision, keep_empty=keep_empty)
            else:
                document = loads(_json_text(data, name))
                result = rnsca.clip_geojson(
                    document, bounds, keep_empty=keep_empty, arrays=True, **options)
                clipped, clip_stats = result
                report = {"stats": clip_stats.to_dict()}
                if verify:
                    bar.phase(f"verifying {name}")
                    verification = rnsca.verify(document, result, bounds, mode=mode,
                                                approx_bound=approx_bound, boundary=boundary)
                    report["verification"] = verification.to_dict()
                text = dumps(clipped, indent=indent) + b"\n"
            _write(output, text, bar)
    finally:
        bar.close()
    with _reporting(EXIT_DATA):
        _write_report(report, stats)
    if verify and not verification.passed:
        _fail(f"verification failed: max_deviation={verification.max_deviation!r} "
              f"(allowed {verification.allowed_deviation!r}), false_positives="
              f"{verification.false_positives}, valid={verification.valid}", EXIT_DATA)



@app.command()
def batch(
    source: Annotated[str, typer.Argument(
        metavar="INPUT", show_default=False,
        help="GeoParquet file (.parquet), FlatGeobuf (.fgb), GeoJSON text sequence "
             "(.geojsons, .geojsonl, .ndjson), a folder of them, or a glob (quoted)")],
    output: Annotated[str, typer.Argument(
        metavar="OUTPUT", show_default=False,
        help="folder of the partitioned GeoParquet output (made if missing; a second "
             "run of the same job into it writes only what is missing)")],
    window: Annotated[str | None, typer.Option(
        "--window", "-w", show_default=False,
        help="xmin,ymin,xmax,ymax, e.g. 0,0,10,10 (this or --windows)")] = None,
    windows: Annotated[Path | None, typer.Option(
        "--windows", show_default=False,
        help="a file of many windows: CSV, a line xmin,ymin,xmax,ymax per window (an "
             "optional header line of those names; # comments), or .json, an array of "
             "[xmin, ymin, xmax, ymax]; each row is clipped to every window it touches, "
             "a row out per window, the window's index (from 0) in --window-column")] = None,
    window_column: Annotated[str, typer.Option(
        help="with --windows: the output column of the window index")] = "window",
    scheduler: Annotated[str | None, typer.Option(
        show_default=False, help=_SCHEDULER_HELP)] = None,
    workers: Annotated[int | None, typer.Option(
        show_default=False, help="worker processes of the local cluster [default: one "
        "per core]")] = None,
    encoding: Annotated[str, typer.Option(
        help="geometry encoding: wkb (any mix of types) or geoarrow (one type per "
             "column; lines and polygons written as multi kinds)")] = "wkb",
    rows_per_partition: Annotated[int, typer.Option(
        help="rows per partition: Parquet row groups are joined up to this many, "
             "FlatGeobuf features cut into ranges of it")] = 500_000,
    bytes_per_partition: Annotated[int, typer.Option(
        help="bytes per partition of a GeoJSON text sequence")] = 128 * 2**20,
    keep_empty: Annotated[bool, typer.Option(
        help="keep rows clipped to nothing (with an empty geometry) instead of dropping "
             "them")] = False,
    method: Annotated[str, typer.Option(help="rnsca, cohen_sutherland, liang_barsky, "
                                             "nicholl_lee_nicholl or midpoint")] = "rnsca",
    n: Annotated[str, typer.Option(help="pieces (runs) per split, 2..64 or auto")] = "auto",
    max_depth: Annotated[int | None, typer.Option(help="0..32")] = None,
    tolerance: Annotated[float | None, typer.Option(help="leaf length")] = None,
    resolution: Annotated[str | None, typer.Option(help=_RESOLUTION_HELP)] = None,
    mode: Annotated[str, typer.Option(help="exact or approx (lines and points only)")] = "exact",
    backend: Annotated[str, typer.Option(help="numba or opencl")] = "numba",
    boundary: Annotated[str, typer.Option(
        help="closed keeps parts on the window's edge (as shapely.intersection); interior "
             "drops them (as shapely.clip_by_rect)")] = "closed",
    progress: Annotated[bool | None, typer.Option(
        "--progress/--no-progress", show_default=False,
        help="show a progress bar on stderr [default: when stderr is a terminal]")] = None,
    stats: Annotated[Path | None, typer.Option(
        "--stats", show_default=False,
        help="write the report JSON to this file instead of stderr")] = None,
) -> None:
    """Clip a dataset to a window (or many) on Dask, into partitioned GeoParquet.

    Each partition of the input (Parquet row groups, FlatGeobuf feature ranges, byte
    ranges of a text sequence) is read, clipped and written by one task, as one
    GeoParquet 1.1 file of OUTPUT (with a bbox covering column), named after the
    partition so the files sort in input order. Rows keep their columns; rows clipped to
    nothing are dropped (unless --keep-empty). With --windows FILE, each row gives one
    row per window its geometry meets (in input order, then window order), with the
    window's index in the file in a column. Each file is written under a temporary
    name, then renamed: a run stopped half-way leaves complete files only, and the same
    command run again writes only the partitions missing.

    Runs on a local cluster of worker processes (one per core) or, with --scheduler, on
    a running Dask cluster whose workers see INPUT and OUTPUT at the same paths. Prints
    the dashboard's address and a progress bar on stderr, then the report (JSON). A
    partition that cannot be read or clipped is reported by file (and row) after the
    others are written; the exit status is then 1.
    """
    if (window is None) == (windows is None):
        _fail("give one of --window xmin,ymin,xmax,ymax and --windows FILE", EXIT_USAGE)
    bounds = _window_bounds(window) if window is not None else None
    options: dict[str, Any] = dict(
        boundary=boundary, method=method, n=int(n) if n.isdigit() else n, max_depth=max_depth,
        tolerance=tolerance, mode=mode, backend=backend)
    try:
        from rnsca import batch as jobs
    except ImportError as exc:
        _fail(f"rnsca batch needs the dask extra: pip install 'rnsca[dask]' ({exc})",
              EXIT_USAGE)
    with _reporting(EXIT_USAGE):
        if resolution is not None:
            options["resolution"] = _resolution(resolution)
        table = jobs.read_windows(windows) if windows is not None else None
        _check_options(bounds if bounds is not None else table[0], options)  # type: ignore[index]
        options = {k: v for k, v in options.items() if v is not None}
        job = jobs.Job(output=str(Path(output).absolute()), window=bounds, windows=table,
                       window_column=window_column, options=options,
                       keep_empty=keep_empty, encoding=jobs.Encoding(encoding.lower()))
        partitions = jobs.plan(jobs.find_inputs(source), rows_per_partition=rows_per_partition,
                               bytes_per_partition=bytes_per_partition)
        # Refuses another job's output, and finds what is left, before a cluster starts.
        todo = jobs.pending(job, partitions)
    if not todo:
        _write_report(jobs.BatchReport(len(partitions), skipped=len(partitions)).to_dict(),
                      stats)
        return
    with _dask_client(scheduler, workers) as (client, threads):
        job = dataclasses.replace(job, threads=threads)
        bar = _PartitionBar(progress, len(todo))
        try:
            with _reporting(EXIT_DATA):
                report = jobs.run(job, partitions, client, on_done=bar.done)
        finally:
            bar.close()
    with _reporting(EXIT_DATA):
        _write_report(report.to_dict(), stats)
    for _, message in report.failed:
        typer.echo(f"error: {' '.join(message.split())}", err=True)
    if report.failed:
        raise typer.Exit(EXIT_DATA)

@app.command()
def glyphs(
    font: Annotated[Path, typer.Argument(
        show_default=False, help="TrueType or OpenType font (.ttf, .otf: glyf or CFF "
        "outlines), WOFF or WOFF2 file")],
    # Required: Typer reads the Ellipsis so (a default must follow `font`'s).
    text: Annotated[str, typer.Option(
        "--text", "-t", show_default=False,
        help="the characters to draw, left to right; a newline starts a new line")
    ] = ...,  # type: ignore[assignment]
    window: Annotated[str, typer.Option(
        "--window", "-w", show_default=False,
        help="xmin,ymin,xmax,ymax in the layout's units, e.g. 0,-16,100,4 with --size 16"
    )] = ...,  # type: ignore[assignment]
    size: Annotated[float | None, typer.Option(
        show_default=False, help="the em in user units (the font size); implies --units "
        "user")] = None,
    units: Annotated[str | None, typer.Option(
        show_default=False, help="font (font units, y up) or user (scaled to --size, y "
        "down as in SVG) [default: user with --size, else font]")] = None,
    origin: Annotated[str, typer.Option(
        help="x,y: where the first glyph's origin (on the baseline) goes")] = "0,0",
    output: Annotated[str | None, typer.Option(
        "--output", "-o", show_default=False,
        help="SVG file to write; default (or -): stdout")] = None,
    stats: Annotated[Path | None, typer.Option(
        "--stats", show_default=False,
        help="write the statistics JSON to this file instead of stderr")] = None,
    fill: Annotated[str, typer.Option(
        help="nonzero (as fonts fill), evenodd, or stroke (outlines as lines)")
    ] = "nonzero",
    curves: Annotated[str, typer.Option(
        help="preserve (Béziers cut at the edges) or flatten (lines)")] = "preserve",
    tolerance: Annotated[float | None, typer.Option(
        help="how far flattened curves may stray (user units)")] = None,
    backend: Annotated[str, typer.Option(help="numba or opencl")] = "numba",
    precision: Annotated[int | None, typer.Option(
        help="significant digits of the written path data [default: exact]")] = None,
) -> None:
    """Draw text from a font file clipped to a window, as a standalone SVG document.

    Glyphs come by code point from the font's cmap and are laid out by advance widths
    (no kerning or shaping), in font units (y up) or scaled to --size (y down). The
    document's viewBox is the window; each glyph with something left is one path,
    filled under the nonzero rule with its curves kept (TrueType quadratics, CFF
    cubics). The statistics go to stderr as JSON (or to --stats FILE).
    """
    bounds = _window_bounds(window)
    with _reporting(EXIT_USAGE):
        place = _point(origin, "--origin")
        if fill.lower() not in ("nonzero", "evenodd", "stroke"):
            raise InvalidOptionError(f"--fill must be nonzero, evenodd or stroke, got {fill!r}")
    if not font.is_file():
        _fail(f"{font}: no such file" if not font.exists() else f"{font}: not a file",
              EXIT_USAGE)
    try:
        with _reporting(EXIT_DATA):
            result = clip_glyphs(font, text, bounds, units=units, size=size, origin=place,
                                 fill=None if fill.lower() == "stroke" else fill,
                                 curves=curves, tolerance=tolerance, backend=backend,
                                 precision=precision)
            _write(output, result.svg().encode("utf-8"), _ProgressBar(False))
            _write_report({"stats": result.stats.to_dict()}, stats)
    except ModuleNotFoundError as error:  # fontTools, or brotli for WOFF2
        _fail(error, EXIT_USAGE)


def _point(text: str, option: str) -> tuple[float, float]:
    """Return the two numbers of an ``x,y`` option."""
    try:
        x, y = (float(part) for part in text.split(","))
    except ValueError:
        raise InvalidOptionError(f"{option} needs two comma-separated numbers x,y, got "
                                 f"{text!r}") from None
    return x, y


@app.command()
def tiles(
    source: Annotated[Path, typer.Argument(
        help="GeoJSON, GeoJSON text sequence (.geojsons/.ndjson: a feature per line), "
             "GeoParquet (.parquet) or FlatGeobuf (.fgb)")],
    output: Annotated[Path, typer.Option(
        "--output", "-o", help="a .pmtiles archive, or a directory for z/x/y.mvt")],
    minzoom: Annotated[int, typer.Option(help="first zoom")] = 0,
    maxzoom: Annotated[int, typer.Option(help="last zoom (at most 24)")] = 14,
    layer: Annotated[str | None, typer.Option(
        help="layer name [default: the input's file name]")] = None,
    buffer: Annotated[int, typer.Option(help="tile units around each tile")] = 64,
    extent: Annotated[int, typer.Option(help="tile units per tile side")] = 4096,
    mode: Annotated[str, typer.Option(help="exact or approx (lines cut within one unit "
                                           "inside the buffer)")] = "exact",
    crs: Annotated[str | None, typer.Option(
        help="EPSG:4326 or EPSG:3857 [default: the input's; GeoJSON is EPSG:4326]")] = None,
    compression: Annotated[str | None, typer.Option(
        help="gzip or none [default: gzip for PMTiles, none for a directory]")] = None,
    validate: Annotated[str, typer.Option(
        help="polygons checked once rounded, invalid ones snapped: at-risk (those not "
             "proved valid), all, or none")] = "at-risk",
    progress: Annotated[bool, typer.Option(help="a progress bar per zoom")] = True,
    summary_json: Annotated[Path | None, typer.Option(
        "--summary-json", help="also write the summary as JSON here")] = None,
    scheduler: Annotated[str | None, typer.Option(
        show_default=False,
        help="build on a running Dask scheduler, e.g. tcp://host:8786 (the dask extra; "
             "OUTPUT is written here, by this process)")] = None,
    workers: Annotated[int | None, typer.Option(
        show_default=False,
        help="build on a local Dask cluster of this many worker processes, as rnsca "
             "batch's [default: in this process, unless --scheduler]")] = None,
    split_zoom: Annotated[int | None, typer.Option(
        show_default=False,
        help="on Dask: the zoom whose tiles' subtrees are the tasks [default: the lowest "
             "with --parts tiles holding features]")] = None,
    parts: Annotated[int | None, typer.Option(
        show_default=False,
        help="on Dask: tasks below the split zoom [default: four per worker]")] = None,
) -> None:
    """Cut features into a vector tile pyramid (MVT 2.1), one clipping pass per zoom.

    Prints a summary: tiles, features, bytes and seconds per zoom.

    With --scheduler or --workers the pyramid is built on Dask (the dask extra): the
    zooms down to a split zoom are cascaded here, then one task builds the subtrees
    below each run of that zoom's tiles, one more the zooms above it (no two tasks build
    the same tile), merged here into one archive, equal to the one built in this
    process. Prints the dashboard's address and a progress bar of the tasks.
    """
    import time

    try:
        from rich.console import Console
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

        from rnsca import tiles as T
        from rnsca.tiles.sources import read_features
    except ImportError as exc:
        _fail(f"rnsca tiles needs the tiles extra: pip install 'rnsca[tiles]' ({exc})",
              EXIT_USAGE)
    on_dask = scheduler is not None or workers is not None
    if not on_dask and (split_zoom is not None or parts is not None):
        _fail("--split-zoom and --parts apply on Dask: give --scheduler or --workers",
              EXIT_USAGE)
    console = Console(stderr=True)
    started = time.perf_counter()
    with _reporting(EXIT_DATA):
        # The parsed properties are acyclic: the collector's full passes over them while
        # they are made are wasted (213 MB of polygons: reading 0.1 s faster).
        with collector_paused():
            features = read_features(source)
        read_seconds = time.perf_counter() - started
        table = features.table(T.Crs(crs) if crs else None)
        name = layer or source.stem
    if on_dask:
        with _reporting(EXIT_USAGE):
            T.check_options(minzoom, maxzoom, extent, buffer, rnsca.Mode(mode))
        summary = _tiles_on_dask(table, output, scheduler, workers, progress,
                                 minzoom=minzoom, maxzoom=maxzoom, extent=extent,
                                 buffer=buffer, layer=name, mode=mode, validate=validate,
                                 compression=compression, split_zoom=split_zoom,
                                 parts=parts)
        _print_tiles_summary(console, source, output, summary, table.count, read_seconds,
                             time.perf_counter() - started, summary_json)
        return
    with _reporting(EXIT_DATA):
        zooms = T.tile_table(table, minzoom=minzoom, maxzoom=maxzoom, extent=extent,
                             buffer=buffer, layer=name, mode=mode, validate=validate)
        pmtiles = output.suffix.lower() == ".pmtiles"
        with Progress(TextColumn("zoom {task.fields[zoom]:>2}"), BarColumn(),
                      TextColumn("{task.completed}/{task.total} zooms, {task.fields[tiles]} "
                                 "tiles"), TimeElapsedColumn(), console=console,
                      disable=not progress) as bar:
            task = bar.add_task("tiles", total=maxzoom - minzoom + 1, zoom=minzoom, tiles=0)
            done = [0]

            def on_zoom(zoom: Any, stored: int) -> None:
                done[0] += len(zoom)
                bar.update(task, advance=1, zoom=min(zoom.zoom + 1, maxzoom), tiles=done[0])

            if pmtiles:
                summary = T.write_pmtiles(output, zooms, layer=name,
                                          compression=compression or "gzip", on_zoom=on_zoom)
            else:
                summary = T.write_directory(output, zooms, compression=compression or "none",
                                            on_zoom=on_zoom)
    _print_tiles_summary(console, source, output, summary, table.count, read_seconds,
                         time.perf_counter() - started, summary_json)


def _tiles_on_dask(table: Any, output: Path, scheduler: str | None, workers: int | None,
                   progress: bool, **options: Any) -> Any:
    """Build the pyramid with `rnsca.dask.tiles`, a bar of its tasks on stderr."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
    )

    try:
        import rnsca.dask
    except ImportError as exc:
        _fail(f"rnsca tiles on Dask needs the dask extra: pip install 'rnsca[dask]' ({exc})",
              EXIT_USAGE)
    with _dask_client(scheduler, workers) as (client, threads), \
            Progress(TextColumn("building tiles"), BarColumn(), MofNCompleteColumn(),
                     TextColumn("tasks"), TimeElapsedColumn(),
                     console=Console(stderr=True), transient=True,
                     disable=not progress) as bar:
        task = bar.add_task("tiles", total=None)

        def on_part(done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        with _reporting(EXIT_DATA):
            return rnsca.dask.tiles(table, output, client=client, threads=threads,
                                    on_part=on_part, **options)


def _print_tiles_summary(console: Any, source: Path, output: Path, summary: Any,
                         features_in: int, read_seconds: float, total: float,
                         summary_json: Path | None) -> None:
    """Print the table of tiles, features, bytes and seconds per zoom; write the JSON."""
    from rich.table import Table

    report = Table(title=f"{source.name} -> {output}")
    for column in ("zoom", "tiles", "features", "bytes", "seconds"):
        report.add_column(column, justify="right")
    for z in summary.zooms:
        report.add_row(str(z["zoom"]), f"{z['tiles']:,}", f"{z['features']:,}",
                       f"{z['bytes']:,}", f"{z['seconds']:.3f}")
    report.add_row("all", f"{summary.tiles:,}",
                   f"{sum(z['features'] for z in summary.zooms):,}", f"{summary.bytes:,}",
                   f"{total:.3f}")
    console.print(report)
    console.print(f"{features_in:,} features read in {read_seconds:.3f} s")
    if summary_json is not None:
        summary_json.write_text(json.dumps({"input": str(source), "output": str(output),
                                            "features_in": features_in,
                                            "read_seconds": read_seconds,
                                            "seconds": total, "zooms": summary.zooms},
                                           indent=2))


def _fail(message: object, code: int) -> NoReturn:
    """Print ``error: message`` on one line of stderr and exit with `code`."""
    text = " ".join(str(message).split())
    typer.echo(f"error: {text}", err=True)
    raise typer.Exit(code)


@contextmanager
def _reporting(code: int) -> Iterator[None]:
    """Turn library and I/O errors into one line on stderr and an exit status.

    Options, windows and backends are the command line's fault (exit 2); anything else
    the library rejects, and failed reads and writes, exit with `code`.
    """
    try:
        yield
    except _USAGE_ERRORS as error:
        _fail(error, EXIT_USAGE)
    except (RnscaError, ValueError) as error:
        _fail(error, code)
    except OSError as error:
        _fail(f"{error.strerror}: {error.filename}" if error.filename and error.strerror
              else error, code)


_SCHEDULER_HELP = ("address of a running Dask scheduler, e.g. tcp://host:8786, whose "
                   "workers see INPUT and OUTPUT at the same paths [default: a local "
                   "cluster of worker processes]")


@contextmanager
def _dask_client(scheduler: str | None, workers: int | None,
                 ) -> Iterator[tuple[Any, int | None]]:
    """Yield a Dask client and each task's threads; print the dashboard's address.

    With `scheduler`, a client of that cluster (threads None: the workers' own);
    otherwise `rnsca.batch.local_cluster` of `workers` processes (one per core by
    default), each task given its share of the cores. Closed on the way out.
    """
    from distributed import Client

    from rnsca import batch as jobs

    if workers is not None and workers < 1:
        _fail(f"--workers must be at least 1, got {workers}", EXIT_USAGE)
    with _reporting(EXIT_DATA):
        cluster = None if scheduler else jobs.local_cluster(workers)
        client = Client(scheduler) if scheduler else Client(cluster)
    threads = None if cluster is None else jobs.threads_per_task(len(cluster.workers))
    typer.echo(f"dashboard: {client.dashboard_link}", err=True)
    try:
        yield client, threads
    finally:
        if cluster is not None:  # first: its workers stop before the client's link goes
            cluster.close()
        client.close()


def _window_bounds(text: str) -> tuple[float, float, float, float]:
    """Return the bounds of ``--window xmin,ymin,xmax,ymax``, or exit 2."""
    parts = text.split(",")
    try:
        if len(parts) != 4:
            raise ValueError
        xmin, ymin, xmax, ymax = (float(part) for part in parts)
    except ValueError:
        _fail(f"--window needs four comma-separated numbers xmin,ymin,xmax,ymax, "
              f"got {text!r}", EXIT_USAGE)
    bounds = (xmin, ymin, xmax, ymax)
    with _reporting(EXIT_USAGE):
        rnsca.Window(*bounds)
    return bounds


_RESOLUTION_HELP = ("approx mode: the output's resolution, which sets the tolerance: a length, "
                    "or <k>px, the window's longer side as k pixels [default: 4096px]")


def _resolution(text: str | None) -> float | str | None:
    """Return a --resolution as the library takes it: a length, or a '<k>px' string."""
    if text is None or text.strip().lower().endswith("px"):
        return text
    try:
        return float(text)
    except ValueError:
        raise InvalidOptionError(f"resolution must be a length > 0 or '<pixels>px' (e.g. "
                                 f"'4096px'), got {text!r}") from None


def _check_options(bounds: tuple[float, float, float, float], options: dict) -> None:
    """Raise the library's error for a bad option before any input is read.

    Clipping no geometry runs every check that does not depend on the input (whether
    approx mode meets a polygon is found when clipping).
    """
    rnsca.clip_ragged("Point", np.empty((0, 2)), (), bounds, **options)


def _clip_svg(data: memoryview, bounds: tuple[float, float, float, float], options: dict,
              geojson_only: dict[str, bool], **svg_options: Any) -> tuple[bytes, dict]:
    """Return the clipped SVG document (UTF-8) and the report.

    Options that only GeoJSON input has (the flags of `geojson_only` that are set) are
    refused; the curve options (method, n, max_depth, mode, backend) are the library's.
    """
    for flag, given in geojson_only.items():
        if given:
            raise InvalidOptionError(f"{flag} applies to GeoJSON input, not to SVG")
    curve_options = {name: options[name] for name in ("method", "n", "max_depth", "mode",
                                                      "backend", "tolerance", "resolution")
                     if name in options}
    text, clip_stats = clip_svg_document(bytes(data), bounds, **svg_options,
                                         **curve_options)
    return text.encode("utf-8"), {"stats": clip_stats.to_dict()}


def _sequence_blocks(path: Path | None, framing: Framing | None
                     ) -> tuple[Framing | None, Iterator[bytes], bytes]:
    """Return the framing and the blocks of input that is a GeoJSON text sequence.

    The framing is `framing` if given, else the file name's; stdin is a sequence if it
    starts with RS. For other input the framing is None, and the third item holds what
    was read of stdin to find that out.
    """
    if path is not None:
        framing = framing or framing_of_path(path.name)
        return framing, _file_blocks(path), b""
    # What has arrived, not a whole block: records piped in slowly are clipped as they come.
    read = getattr(sys.stdin.buffer, "read1", sys.stdin.buffer.read)
    rest = iter(lambda: read(_BLOCK), b"")
    if framing is not None:
        return framing, rest, b""
    first = next(rest, b"")
    start = _NON_SPACE.search(first)
    if start is None or first[start.start():start.start() + 1] != RS:
        return None, rest, first
    return Framing.RS, itertools.chain([first], rest), b""


def _file_blocks(path: Path) -> Iterator[bytes]:
    with _reporting(EXIT_DATA), open(path, "rb") as stream:
        while block := stream.read(_BLOCK):
            yield block


def _clip_sequence(pieces: Iterator[bytes], framing: Framing,
                   bounds: tuple[float, float, float, float], options: dict,
                   keep_empty: bool, output: str | None) -> dict:
    """Clip a sequence a chunk at a time, writing each chunk's records; return the report.

    The output is flushed after each chunk, so a reader downstream gets records as they
    are clipped, and a bad record leaves those before it written.
    """
    to_stdout = output is None or output == "-"
    with _reporting(EXIT_DATA):
        stream = sys.stdout.buffer if to_stdout else open(str(output), "wb")  # noqa: SIM115
    try:
        with _reporting(EXIT_DATA):
            clipped = rnsca.clip_geojson_seq(
                split_records(pieces, framing), bounds, keep_empty=keep_empty,
                arrays=True, **options)
            chunks = 0
            for record in clipped:
                write_records([record], stream, framing)
                if clipped.chunks != chunks:
                    chunks = clipped.chunks
                    stream.flush()
            stream.flush()
    finally:
        if not to_stdout:
            stream.close()
    assert clipped.stats is not None
    return {"stats": clipped.stats.to_dict(), "records_in": clipped.records_in,
            "records_out": clipped.records_out, "chunks": clipped.chunks}


def _is_svg(path: Path | None, data: memoryview) -> bool:
    """Return whether the input is SVG: by its name, else by its first character."""
    if path is not None and path.suffix.lower() in SVG_SUFFIXES:
        return True
    if data[:3] == b"\xef\xbb\xbf":  # a UTF-8 byte order mark
        data = data[3:]
    first = _NON_SPACE.search(data)
    return first is not None and first.group() == b"<"


def _input(source: str | None) -> tuple[str, Path | None]:
    """Return the name to report and the path of the input (None: stdin), or exit 2."""
    if source is None and sys.stdin.isatty():
        _fail("no INPUT: name a GeoJSON or SVG file, or pipe one to stdin", EXIT_USAGE)
    if source is None or source == "-":
        return "<stdin>", None
    path = Path(source)
    if path.suffix and path.suffix.lower() not in (GEOJSON_SUFFIXES + SVG_SUFFIXES
                                                   + SEQUENCE_SUFFIXES):
        _fail(f"{source}: only GeoJSON or SVG input is accepted (a .geojson, .json or .svg "
              f"file, a GeoJSON text sequence .geojsons, .geojsonl or .ndjson, or either "
              f"on stdin), got a {path.suffix} file", EXIT_USAGE)
    if not path.is_file():
        _fail(f"{source}: no such file" if not path.exists() else f"{source}: not a file",
              EXIT_USAGE)
    return source, path


def _read(path: Path | None, bar: _ProgressBar, prefix: bytes = b"") -> memoryview:
    """Return the bytes of the input file (stdin for None, after `prefix` read of it)."""
    if path is None:
        stream: BinaryIO = sys.stdin.buffer
        return _read_blocks(stream, None, "<stdin>", bar, prefix)
    with open(path, "rb") as stream:
        return _read_blocks(stream, path.stat().st_size, str(path), bar)


def _read_blocks(stream: BinaryIO, size: int | None, name: str,
                 bar: _ProgressBar, prefix: bytes = b"") -> memoryview:
    bar.phase(f"reading {name}", size)
    buffer = bytearray(prefix)
    while block := stream.read(_BLOCK):
        buffer += block
        bar.advance(len(block), read=len(buffer))
    return memoryview(buffer)


def _json_text(data: memoryview, name: str) -> memoryview:
    """Return `data` without a byte order mark; exit unless it starts with a JSON object.

    Anything else (SVG was routed before; WKT, a shapefile...) is refused here, before
    parsing, with a message that says so.
    """
    if data[:3] == b"\xef\xbb\xbf":  # a UTF-8 byte order mark, which RFC 8259 allows
        data = data[3:]
    first = _NON_SPACE.search(data)
    if first is None:
        _fail(f"{name} is empty: expected a GeoJSON object", EXIT_DATA)
    if first.group() != b"{":
        start = bytes(data[first.start():first.start() + 16])
        _fail(f"{name}: only GeoJSON or SVG input is accepted (a JSON object: Geometry, "
              f"Feature or FeatureCollection; or an SVG document), but it starts with "
              f"{start!r}", EXIT_USAGE)
    return data


def _write(output: str | None, text: bytes, bar: _ProgressBar) -> None:
    """Write `text` to the output file, or to stdout for None or ``-``."""
    if output is None or output == "-":
        _write_blocks(sys.stdout.buffer, text, "<stdout>", bar)
        sys.stdout.buffer.flush()
        return
    with open(output, "wb") as stream:
        _write_blocks(stream, text, output, bar)


def _write_blocks(stream: BinaryIO, text: bytes, name: str, bar: _ProgressBar) -> None:
    bar.phase(f"writing {name}", len(text))
    view = memoryview(text)
    for start in range(0, len(view), _BLOCK):
        block = view[start:start + _BLOCK]
        stream.write(block)
        bar.advance(len(block))


def _write_report(report: dict, path: Path | None) -> None:
    text = json.dumps(report, separators=(",", ":"))
    if path is None:
        typer.echo(text, err=True)
    else:
        path.write_text(text + "\n")


class _ProgressBar:
    """A progress bar on stderr, through the phases of a command (rich, via Typer).

    `enabled` True shows it, False never; None shows it once the input is known to hold
    at least `PROGRESS_MIN_BYTES` and only when stderr is a terminal. It is transient:
    it leaves nothing behind on the terminal.
    """

    def __init__(self, enabled: bool | None) -> None:
        self.enabled = enabled
        self._progress: Progress | None = None
        self._task: TaskID  # set with `_progress`
        self._phase: tuple[str, int | None] = ("", None)

    def phase(self, description: str, total: int | None = None) -> None:
        """Start a phase: its description, and its size in bytes if it has one."""
        self._phase = (description, total)
        if total is not None:
            self._start_if(total)
        if self._progress is not None:
            self._progress.update(self._task, description=description, total=total,
                                  completed=0)

    def advance(self, amount: int, *, read: int = 0) -> None:
        """Count `amount` bytes of the phase done; `read` is the input read so far."""
        if self._progress is None and read:
            self._start_if(read)
            if self._progress is not None:
                self._progress.update(self._task, completed=read)
                return
        if self._progress is not None:
            self._progress.advance(self._task, amount)

    def close(self) -> None:
        """Remove the bar."""
        if self._progress is not None:
            self._progress.stop()
            self._progress = None

    def _start_if(self, size: int) -> None:
        if self._progress is not None or self.enabled is False:
            return
        if self.enabled is None and not (size >= PROGRESS_MIN_BYTES and sys.stderr.isatty()):
            return
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            DownloadColumn,
            Progress,
            SpinnerColumn,
            TextColumn,
            TimeElapsedColumn,
        )

        self._progress = Progress(
            SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
            DownloadColumn(), TimeElapsedColumn(),
            console=Console(stderr=True), transient=True)
        self._progress.start()
        description, total = self._phase
        self._task = self._progress.add_task(description, total=total)



class _PartitionBar:
    """A progress bar of a batch job's partitions on stderr (rich), transient.

    `enabled` None shows it when stderr is a terminal.
    """

    def __init__(self, enabled: bool | None, total: int) -> None:
        self._progress: Progress | None = None
        if enabled is False or (enabled is None and not sys.stderr.isatty()):
            return
        from rich.console import Console
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeElapsedColumn,
            TimeRemainingColumn,
        )

        self._progress = Progress(
            TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
            TextColumn("partitions, {task.fields[rows]:,} rows"), TimeElapsedColumn(),
            TimeRemainingColumn(), console=Console(stderr=True), transient=True)
        self._progress.start()
        self._task = self._progress.add_task("clipping", total=total, rows=0)
        self._rows = 0

    def done(self, partition: Any, report: Any, error: str | None) -> None:
        """Count one partition finished (its report, or its error)."""
        if self._progress is None:
            return
        if report is not None:
            self._rows += report.rows_in
        self._progress.update(self._task, advance=1, rows=self._rows)

    def close(self) -> None:
        """Remove the bar."""
        if self._progress is not None:
            self._progress.stop()
            self._progress = None

if __name__ == "__main__":  # pragma: no cover
    app()
