"""``python -m service.healthcheck``: exit 0 if ``/healthz`` answers 200 (Docker HEALTHCHECK).

The slim image has no curl; this uses only the standard library.
"""

from __future__ import annotations

import os
import sys
import urllib.request

__all__ = ["check"]


def check(port: int, timeout: float = 3.0) -> bool:
    """Return whether ``http://127.0.0.1:<port>/healthz`` answers 200 within `timeout`."""
    try:
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/healthz", timeout=timeout) as r:
            return r.status == 200
    except OSError:
        return False


if __name__ == "__main__":
    sys.exit(0 if check(int(os.environ.get("RNSCA_PORT", "8000"))) else 1)
