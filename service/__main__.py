"""``python -m service``: the Docker image's entry point (settings from ``RNSCA_*``)."""

from service.serve import serve

if __name__ == "__main__":
    serve()
