"""Backends: one interface (`ClipBackend`), several places to run the kernels."""
