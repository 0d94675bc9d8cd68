"""The routers: ``/v1`` (clipping, capabilities), operations, the API docs, the playground."""

from fastapi import APIRouter

from service.routes import clip, docs, health, meta, playground, tiles

__all__ = ["api_router"]

# Each router carries its whole prefix (no nesting), so a route's `path` is its full
# template, which the access log and the metrics use as the route label.
api_router = APIRouter()
api_router.include_router(clip.router)
api_router.include_router(tiles.router)
api_router.include_router(meta.v1_router)
api_router.include_router(health.router)
api_router.include_router(meta.router)
api_router.include_router(docs.router)
api_router.include_router(playground.router)
