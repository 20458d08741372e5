"""Compiled (numba) kernel of the learning layer's twin (placeholder until written)."""

from ..lib.kernel import available

__all__ = ["available"]
