"""Readers and writers of geometry text formats; they know nothing of clipping.

Import the format modules directly, e.g. ``from rnsca.formats.geojson import from_geojson``.
"""

__all__: list[str] = []
