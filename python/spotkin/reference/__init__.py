"""Pure-Python reference implementations: plain NumPy and ``math``, one sample at a time.

Slow and obvious on purpose. Each function is written straight from the formula
it cites, so the tests can check the C++ core against it.
"""
