"""NumPy references of every kernel family, for tests and benchmarks only.

Each function takes NumPy arrays and *returns* its outputs (no ``out=``), and
is written for clarity, not speed.
"""
