"""Verification: clipped output compared with Shapely's exact intersection (the oracle).

`verify` (in `rnsca.verify.geometry`) covers segments, geometries, GeoJSON and paths;
`rnsca.verify.paths` turns paths into Shapely geometries for it.
"""

from rnsca.verify.geometry import Verification, approx_leaf_bound, verify

__all__ = ["Verification", "approx_leaf_bound", "verify"]
