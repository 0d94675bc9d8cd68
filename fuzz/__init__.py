"""Coverage-guided fuzzers (atheris, libFuzzer) of the readers and the binary endpoint.

One module per target; each defines ``MAX_LEN`` (the longest input libFuzzer makes),
``setup()`` (compile the kernels and build what every input needs, once) and
``test_one_input(data)``, which raises on a finding: an exception the target does not
document, or a disagreement with the target's reference. `fuzz.run` runs them under
atheris; ``tests/fuzz`` replays the committed corpora through ``test_one_input``.
See ``fuzz/README.md``.
"""

#: The targets, by module name under ``fuzz``.
TARGETS = ("svg_path", "svg_document", "geojson_reader", "geojson_file", "segments_endpoint")
