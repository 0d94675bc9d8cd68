"""Benchmarks for rnsca: seeded workloads, timed runs, JSON results and plots.

Run everything with ``make bench`` (``python -m benchmarks.run``); see benchmarks/README.md.
"""
