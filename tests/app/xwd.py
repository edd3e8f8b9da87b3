"""Read an X Window Dump (XWD) file, as written by ``Xvfb -fbdir``, into an RGB numpy array."""

from __future__ import annotations

import numpy as np

_FIELDS = ("header_size", "file_version", "pixmap_format", "pixmap_depth", "pixmap_width",
           "pixmap_height", "xoffset", "byte_order", "bitmap_unit", "bitmap_bit_order", "bitmap_pad",
           "bits_per_pixel", "bytes_per_line", "visual_class", "red_mask", "green_mask", "blue_mask",
           "bits_per_rgb", "colormap_entries", "ncolors", "window_width", "window_height", "window_x",
           "window_y", "window_bdrwidth")


def read_xwd(path) -> np.ndarray:
    """(height, width, 3) uint8 RGB of a 24/32-bit TrueColor XWD file."""
    data = open(path, "rb").read()
    head = dict(zip(_FIELDS, np.frombuffer(data[:100], ">u4").tolist()))
    if head["bits_per_pixel"] != 32:
        raise ValueError(f"only 32 bits per pixel supported, got {head['bits_per_pixel']}")
    off = head["header_size"] + 12 * head["ncolors"]
    h, w, bpl = head["pixmap_height"], head["pixmap_width"], head["bytes_per_line"]
    raw = np.frombuffer(data, np.uint8, count=h * bpl, offset=off).reshape(h, bpl)[:, :4 * w]
    px = raw.reshape(h, w, 4).view("<u4" if head["byte_order"] == 0 else ">u4")[..., 0]
    out = np.empty((h, w, 3), np.uint8)
    for i, key in enumerate(("red_mask", "green_mask", "blue_mask")):
        mask = head[key]
        shift = (mask & -mask).bit_length() - 1
        out[..., i] = (px & mask) >> shift
    return out
