"""splatedit: a point-splat shape editor.

Implements Botsch & Kobbelt, "Real-Time Shape Editing using Radial Basis
Functions" (Eurographics 2005) on elliptical surface splats, with its own Vulkan
EWA splat renderer.

Data flows one way: file (``splatedit.io``) -> model (``splatedit.model``) ->
selection (``splatedit.select``) -> constraints and bases (``splatedit.deform``)
-> GPU (``splatedit.render``) -> screen (``splatedit.app``).
"""

__version__ = "0.1.0"
