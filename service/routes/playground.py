"""``GET /``: the playground page, and its scripts, styles and examples under ``/playground``.

Static files only (no build step, nothing from a CDN), kept out of the OpenAPI schema.
"""

from __future__ import annotations

from pathlib import Path

from fastapi import APIRouter
from starlette.responses import FileResponse
from starlette.staticfiles import StaticFiles

__all__ = ["router", "STATIC_DIR", "assets"]

#: The page and its assets (package data of `service`).
STATIC_DIR = Path(__file__).resolve().parent.parent / "static"

router = APIRouter(include_in_schema=False)


@router.get("/", include_in_schema=False)
async def playground() -> FileResponse:
    """Return the playground page."""
    return FileResponse(STATIC_DIR / "index.html", media_type="text/html; charset=utf-8")


def assets() -> StaticFiles:
    """Return the app serving the page's assets, to mount at ``/playground``."""
    return StaticFiles(directory=STATIC_DIR)
