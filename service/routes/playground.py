"""``GET /``: the playground page; ``GET /playground/...``: its scripts, styles and examples.

``GET /favicon.ico`` is the service's icon (an SVG, also linked from the pages).
Static files only (no build step, nothing from a CDN), kept out of the OpenAPI schema.
The assets are a route (not a mount) so that the access log and the metrics label them
with their route like every other request.
"""

from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter, Request
from starlette.responses import FileResponse, Response
from starlette.staticfiles import StaticFiles

__all__ = ["router", "STATIC_DIR"]

#: The page and its assets (package data of `service`).
STATIC_DIR = Path(__file__).resolve().parent.parent / "static"
_FILES = StaticFiles(directory=STATIC_DIR)  # path checks, ETag and 304, media types

router = APIRouter(include_in_schema=False)


@router.get("/")
async def playground() -> FileResponse:
    """Return the playground page."""
    return FileResponse(STATIC_DIR / "index.html", media_type="text/html; charset=utf-8")


@router.get("/favicon.ico")
async def favicon() -> FileResponse:
    """Return the service's icon (SVG: browsers ask for /favicon.ico whatever it is)."""
    return FileResponse(STATIC_DIR / "favicon.svg", media_type="image/svg+xml")


@router.get("/playground/{path:path}")
async def asset(path: str, request: Request) -> Response:
    """Return one of the page's files (404, as a problem, for anything else)."""
    return await _FILES.get_response(path, request.scope)
