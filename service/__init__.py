"""The rnsca HTTP service: a FastAPI app over the `rnsca` library (see README.md).

`create_app` builds the app from `Settings`; `serve` runs it under uvicorn.
"""

from service.config import Settings
from service.main import create_app

__all__ = ["Settings", "create_app"]
