"""``GET /docs`` (Swagger UI) and ``GET /redoc`` (ReDoc), with their assets served from here.

FastAPI's own pages load Swagger UI and ReDoc from a CDN, so without internet they stay
blank. Their scripts and styles come from the package `fastapi-offline` (a copy of
swagger-ui-dist 5 and redoc 2, kept up to date with the CDN's), served under
``/docs/assets/``; the pages are FastAPI's `get_swagger_ui_html` and `get_redoc_html`
pointed there, with Google Fonts off and the service's own icon, so nothing is fetched
from another origin. Like the playground's files, the assets are a route (not a mount),
so the access log and the metrics label them with their route.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

from fastapi import APIRouter, Request
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from starlette.responses import HTMLResponse, Response
from starlette.staticfiles import StaticFiles

__all__ = ["router", "ASSETS_DIR"]

#: swagger-ui-bundle.js, swagger-ui.css and redoc.standalone.js, as the package ships them.
ASSETS_DIR = Path(str(files("fastapi_offline") / "static"))
_FILES = StaticFiles(directory=ASSETS_DIR)  # path checks, ETag and 304, media types
_ASSETS = "/docs/assets/"
_ICON = "/favicon.ico"
_OPENAPI = "/openapi.json"

router = APIRouter(include_in_schema=False)


def _root(request: Request) -> str:
    """Return the prefix a proxy mounts the app under ("" when served at the root)."""
    return str(request.scope.get("root_path", "")).rstrip("/")


@router.get("/docs")
async def swagger_ui(request: Request) -> HTMLResponse:
    """Return the Swagger UI page of the API."""
    root = _root(request)
    return get_swagger_ui_html(
        openapi_url=root + _OPENAPI, title="rnsca API - Swagger UI",
        swagger_js_url=root + _ASSETS + "swagger-ui-bundle.js",
        swagger_css_url=root + _ASSETS + "swagger-ui.css",
        swagger_favicon_url=root + _ICON,
        # No badge from the online validator (validator.swagger.io).
        swagger_ui_parameters={"validatorUrl": None})


@router.get("/redoc")
async def redoc(request: Request) -> HTMLResponse:
    """Return the ReDoc page of the API."""
    root = _root(request)
    return get_redoc_html(
        openapi_url=root + _OPENAPI, title="rnsca API - ReDoc",
        redoc_js_url=root + _ASSETS + "redoc.standalone.js",
        redoc_favicon_url=root + _ICON, with_google_fonts=False)


@router.get(_ASSETS + "{path:path}")
async def asset(path: str, request: Request) -> Response:
    """Return one of the pages' scripts or styles (404, as a problem, for anything else)."""
    return await _FILES.get_response(path, request.scope)
