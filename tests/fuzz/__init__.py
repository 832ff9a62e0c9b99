"""The fuzz harness of ``tests/test_fuzz.py``: spotkin's public API, every callable described by its
argument slots, fed hostile inputs in worker processes and judged against the documentation."""
