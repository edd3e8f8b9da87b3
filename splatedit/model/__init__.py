"""The splat arrays and their invariants."""

from splatedit.model.cloud import SplatCloud

__all__ = ["SplatCloud"]
