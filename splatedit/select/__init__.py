"""Selections of splats: geometric regions (edit scripts) and brush painting (editor)."""

from splatedit.select.regions import Box, Indices, Region, Sphere

__all__ = ["Box", "Indices", "Region", "Sphere"]
