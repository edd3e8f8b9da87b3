"""The helpers both renderers share to go from model units to GPU units
(splatedit/render/gpu_units.py) and to clip a pick rectangle (targets.py)."""

import numpy as np
import pytest

from splatedit.errors import ParameterError
from splatedit.render.gpu_units import MAX_GROUPS, pack_basis_rows, pack_deform_block, selection_flags, unit_scale
from splatedit.render.targets import clip_rect


def test_deform_block_holds_column_4g_plus_j_component_i_at_row_3g_plus_i():
    rng = np.random.default_rng(1)
    dC = rng.normal(size=(6, 3)) * 1e3
    scale = 512.0
    block = pack_deform_block(dC, None, scale)
    assert block.dtype == np.float32 and block.shape == (48 * MAX_GROUPS // 4 + 64 * MAX_GROUPS // 4,)
    rows = block[:12 * MAX_GROUPS].reshape(3 * MAX_GROUPS, 4)
    for k in range(6):
        g, j = divmod(k, 4)
        for i in range(3):
            assert rows[3 * g + i, j] == np.float32(dC[k, i] / scale)
    assert not rows[3 * 1 + 0, 2:].any() and not rows[6:].any()      # zero padding after column 5
    assert not block[12 * MAX_GROUPS:].any()                           # no rotations


def test_basis_rows_scale_the_gradients_only_and_pad_to_groups_of_four():
    rng = np.random.default_rng(2)
    mats = [rng.normal(size=(5, 6)) for _ in range(4)]
    rows = pack_basis_rows(mats, 4.0)
    assert rows.shape == (5, 2, 4, 4)
    np.testing.assert_array_equal(rows[:, 0, 0, :], mats[0][:, :4].astype(np.float32))
    np.testing.assert_array_equal(rows[:, 1, 2, :2], (mats[2][:, 4:] * 4.0).astype(np.float32))
    assert not rows[:, 1, :, 2:].any()
    assert pack_basis_rows([np.zeros((0, 3))] * 4, 1.0).shape == (1, 1, 4, 4)   # never an empty buffer


def test_selection_flags_agree_for_masks_and_indices_and_mark_inactive_handles():
    n = 10
    sup = np.zeros(n, bool)
    sup[[1, 2, 3]] = True
    a = selection_flags(n, sup, [2], [7])
    b = selection_flags(n, [1, 2, 3], np.arange(n) == 2, np.arange(n) == 7)
    np.testing.assert_array_equal(a, b)
    assert list(a[[0, 1, 2, 7]]) == [0, 1, 3, 2 | 8]
    with pytest.raises(ParameterError, match="handle_mask"):
        selection_flags(n, None, [n])
    with pytest.raises(ParameterError, match="support_mask"):
        selection_flags(n, np.ones(n + 1, bool))


def test_unit_scale_is_the_power_of_two_nearest_the_size():
    assert unit_scale(3.0, 0.1) == 4.0
    assert unit_scale(1e-12, 0.0) == 2.0 ** round(np.log2(1e-12))
    assert unit_scale(0.0, 0.0) == 1.0 and unit_scale(np.inf, 0.0) == 1.0


def test_pick_rect_is_clipped_to_the_image_and_an_outside_rect_is_refused():
    assert clip_rect(None, 64, 32) == (0, 0, 64, 32)
    assert clip_rect((-5, 30, 20, 10), 64, 32) == (0, 30, 15, 2)
    with pytest.raises(ParameterError, match="rect"):
        clip_rect((64, 0, 5, 5), 64, 32)
