"""The ``rnsca`` command line."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

import rnsca
from rnsca.backends.registry import available_backends, get_backend
from rnsca.errors import RnscaError

app = typer.Typer(help="Clip geometry against a rectangular window.", no_args_is_help=True)


@app.command()
def backends() -> None:
    """List the backends that can run here."""
    for kind in available_backends():
        typer.echo(kind.value)


@app.command()
def warm_up() -> None:
    """Compile the kernels into the on-disk cache (later processes load them)."""
    for kind in available_backends():
        engine = get_backend(kind)
        if hasattr(engine, "warm_up"):
            engine.warm_up()
    typer.echo("kernels ready")


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
    mode: Annotated[str, typer.Option(help="exact or approx")] = "exact",
    backend: Annotated[str, typer.Option(help="numba or numpy")] = "numba",
    verify: Annotated[bool, typer.Option(help="compare with Shapely")] = False,
) -> None:
    """Clip the segments of a .npy file and print the statistics as JSON."""
    try:
        data = np.load(source, allow_pickle=False)
        result = rnsca.clip_segments(
            data, window, method=method, n=int(n) if n.isdigit() else n,
            max_depth=max_depth, tolerance=tolerance, mode=mode, backend=backend)
    except (RnscaError, ValueError, OSError) as exc:
        typer.echo(f"error: {exc}", err=True)
        raise typer.Exit(2) from None
    np.savez(output, segments=result.segments, source=result.source, t=result.t)
    report = {"stats": result.stats.to_dict(), "method": result.method.value,
              "mode": result.mode.value, "backend": result.backend.value}
    if verify:
        report["verification"] = rnsca.verify(data, result, window).to_dict()
    typer.echo(json.dumps(report, indent=2))


if __name__ == "__main__":  # pragma: no cover
    app()
