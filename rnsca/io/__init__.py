"""Readers and writers of geometry text formats; they know nothing of clipping.

Import the format modules directly, e.g. ``from rnsca.io.geojson import from_geojson``
or ``from rnsca.io.svgpath import parse_paths``.
"""

__all__: list[str] = []
