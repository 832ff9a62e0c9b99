"""A six-legged test robot for tests that import it from here; the fuzz harness is ``tests/fuzz/``."""

from fuzz.urdf_texts import HEXAPOD_URDF

__all__ = ["HEXAPOD_URDF"]
