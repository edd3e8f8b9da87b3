"""The transform fields show lengths to 1e-4 of the model's diagonal, so the
three fields of a 1280x720 panel are not cut off ("-0.00060034" was)."""

from __future__ import annotations

from splatedit.app.ui.gui_transform import length_format


def test_lengths_are_shown_to_a_fixed_share_of_the_diagonal():
    assert length_format(1.6) % -0.00060034 == "-0.0006"          # the bundled bunny
    assert length_format(229.0) % 12.3456 == "12.35"               # a scanned figure in mm
    assert length_format(1e5) % 123.456 == "123"
    assert length_format(1e-3) % 1.23456789e-5 == "0.000012"       # at most 6 decimals


def test_a_field_of_the_bunny_fits_its_width():
    """At the panel's 7 px per character, a third of the 220 px float3 field
    (about 70 px minus the frame padding) holds 9 characters."""
    for v in (-0.00060034, 0.27986, -0.4989, 12.0):
        assert len(length_format(1.6) % v) <= 8
