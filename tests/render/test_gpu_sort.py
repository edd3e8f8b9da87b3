"""The GPU radix sort (splatedit.render.gaussian.gpu_sort) equals numpy's stable
argsort exactly -- keys and values -- on random keys, heavy duplicates, n not
a multiple of the workgroup or block, n = 0 and 1, and 1M pairs, in both
scatter variants; it sorts the count it reads from the GPU buffer (clamped to
its capacity) and leaves the rest alone; the 16-bit variant orders keys below
2**16; the bitonic baseline sorts too; float keys map to an order-preserving uint."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.gaussian.gpu_sort import (RADIX_BLOCK, BitonicSort, RadixSort, sortable_float_keys,
                                       subgroup_scatter_supported)


@pytest.fixture(scope="module")
def gpu():
    dev = V.Device()
    cache = V.PipelineCache(dev)
    yield dev, cache
    cache.destroy()
    dev.close()


def _modes(dev):
    return ["shared"] + (["subgroup"] if subgroup_scatter_supported(dev) else [])


def _sort_on_gpu(gpu, keys, values=None, *, mode="auto", count=None, capacity=None, bits=32):
    """(keys, values) after the GPU sort of the buffers holding ``keys`` (all
    of them, the first ``count`` sorted) and ``values`` (default: indices)."""
    dev, cache = gpu
    n = len(keys)
    capacity = capacity or max(n, 1)
    values = np.arange(n, dtype=np.uint32) if values is None else values
    kb = V.Buffer(dev, 4 * max(n, 1), ("storage",), host_visible=True)
    vb = V.Buffer(dev, 4 * max(n, 1), ("storage",), host_visible=True)
    cb = V.Buffer(dev, 16, ("storage",), host_visible=True)
    s = None
    try:
        kb.view(np.uint32)[:n] = keys
        vb.view(np.uint32)[:n] = values
        cb.view(np.uint32)[:] = (7, n if count is None else count, 7, 7)
        s = RadixSort(dev, cache, kb, vb, cb, capacity=capacity, count_index=1, mode=mode)
        dev.submit(lambda c: s.record(c, bits=bits))
        return kb.view(np.uint32)[:n].copy(), vb.view(np.uint32)[:n].copy()
    finally:
        for o in (s, cb, vb, kb):
            if o is not None:
                o.destroy()


def _assert_stable_sorted(keys, got_keys, got_values):
    order = np.argsort(keys, kind="stable")
    np.testing.assert_array_equal(got_keys, keys[order])
    np.testing.assert_array_equal(got_values, order.astype(np.uint32))


CASES = {
    "random_not_a_block_multiple": lambda rng: rng.integers(0, 2**32, 3 * RADIX_BLOCK + 77, dtype=np.uint64),
    "duplicates": lambda rng: rng.integers(0, 5, 5000) * 0x01010101 + (rng.integers(0, 2, 5000) << 31),
    "one_value": lambda rng: np.full(1000, 0xDEADBEEF),
    "n_0": lambda rng: np.zeros(0),
    "n_1": lambda rng: np.array([123456789]),
    "n_255": lambda rng: rng.integers(0, 2**32, 255, dtype=np.uint64),
}


@pytest.mark.parametrize("case", list(CASES))
def test_radix_sort_equals_numpy_stable_argsort(gpu, case):
    keys = CASES[case](np.random.default_rng(7)).astype(np.uint32)
    for mode in _modes(gpu[0]):
        _assert_stable_sorted(keys, *_sort_on_gpu(gpu, keys, mode=mode))


def test_radix_sort_of_a_million_pairs_is_exact(gpu):
    keys = np.random.default_rng(8).integers(0, 2**32, 1 << 20, dtype=np.uint64).astype(np.uint32)
    _assert_stable_sorted(keys, *_sort_on_gpu(gpu, keys))


def test_radix_sort_sorts_the_count_read_on_the_gpu_and_keeps_the_rest(gpu):
    keys = np.random.default_rng(9).integers(0, 2**32, 10_000, dtype=np.uint64).astype(np.uint32)
    got_k, got_v = _sort_on_gpu(gpu, keys, count=3001)
    _assert_stable_sorted(keys[:3001], got_k[:3001], got_v[:3001])
    np.testing.assert_array_equal(got_k[3001:], keys[3001:])
    # a count above the capacity is clamped to it
    got_k, got_v = _sort_on_gpu(gpu, keys, count=10**9, capacity=4000)
    _assert_stable_sorted(keys[:4000], got_k[:4000], got_v[:4000])
    np.testing.assert_array_equal(got_k[4000:], keys[4000:])


def test_radix_sort_of_16_bit_keys_takes_two_passes_and_orders_them(gpu):
    keys = np.random.default_rng(10).integers(0, 1 << 16, 20_000).astype(np.uint32)
    _assert_stable_sorted(keys, *_sort_on_gpu(gpu, keys, bits=16))
    with pytest.raises(ParameterError):
        _sort_on_gpu(gpu, keys, bits=24)


def test_bitonic_sort_orders_a_power_of_two(gpu):
    dev, cache = gpu
    keys = np.random.default_rng(11).integers(0, 2**32, 4096, dtype=np.uint64).astype(np.uint32)
    kb = V.Buffer(dev, 4 * 4096, ("storage",), host_visible=True)
    vb = V.Buffer(dev, 4 * 4096, ("storage",), host_visible=True)
    b = BitonicSort(dev, cache, kb, vb)
    try:
        kb.view(np.uint32)[:] = keys
        vb.view(np.uint32)[:] = np.arange(4096)
        dev.submit(lambda c: b.record(c, 4096))
        np.testing.assert_array_equal(kb.view(np.uint32), np.sort(keys))
        np.testing.assert_array_equal(keys[vb.view(np.uint32)], np.sort(keys))
    finally:
        b.destroy()
        vb.destroy()
        kb.destroy()


def test_sortable_float_keys_order_as_the_floats():
    x = np.array([-np.inf, -3.5, -1e-30, -0.0, 0.0, 1e-30, 2.0, 7.5e30, np.inf], np.float32)
    k = sortable_float_keys(x)
    assert np.all(np.diff(k.astype(np.int64)) >= 0)
    rng = np.random.default_rng(12)
    y = (rng.normal(size=5000) * 10.0 ** rng.integers(-20, 20, 5000)).astype(np.float32)
    np.testing.assert_array_equal(np.sort(y), y[np.argsort(sortable_float_keys(y), kind="stable")])


def test_radix_sort_rejects_bad_arguments(gpu):
    dev, cache = gpu
    b = V.Buffer(dev, 64, ("storage",), host_visible=True)
    try:
        with pytest.raises(ParameterError):
            RadixSort(dev, cache, b, b, b, capacity=100)          # buffers too small
        with pytest.raises(ParameterError):
            RadixSort(dev, cache, b, b, b, capacity=4, mode="fast")
        with pytest.raises(ParameterError):
            RadixSort(dev, cache, b, b, b, capacity=4, count_index=16)
    finally:
        b.destroy()
