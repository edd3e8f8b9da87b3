"""Issue 21: property-based fuzzing of every reader.  Random headers and
bodies (hypothesis, derandomized: the same cases on every run) must end in a
cloud or in one :class:`InputError` line naming the file, never another
exception, a hang or a runaway allocation: each case is bounded in time and
in traced memory, and the address space of the whole run is capped (a
header-driven allocation the readers failed to bound would end in
"not enough memory", which the check refuses too)."""

from __future__ import annotations

import contextlib
import resource
import struct
import tempfile
import time
import tracemalloc
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from splatedit.errors import InputError, InputWarning
from splatedit.io import read

#: wall-clock bound of one case (s): every file here is under 10 kB; the
#: slowest legitimate case (a first read importing scipy) takes about 1 s
CASE_SECONDS = 10.0
#: traced (numpy and Python) memory bound of one case
CASE_BYTES = 64 * 2**20
#: address space the process may grow by during a test (the net for
#: allocations tracemalloc does not see: laspy's Rust codec, libE57)
EXTRA_ADDRESS_SPACE = 2 * 2**30

FUZZ = settings(max_examples=30, deadline=None, derandomize=True, database=None,
                suppress_health_check=list(HealthCheck))


@pytest.fixture(scope="module")
def workdir():
    with tempfile.TemporaryDirectory(prefix="splatedit-fuzz-") as d:
        yield Path(d)


@contextlib.contextmanager
def capped_address_space():
    """Lower the soft RLIMIT_AS to the current size plus EXTRA_ADDRESS_SPACE
    for the block (raised back after: the hard limit is untouched)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    with open("/proc/self/statm") as fh:
        current = int(fh.read().split()[0]) * resource.getpagesize()
    cap = current + EXTRA_ADDRESS_SPACE
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


def read_bounded(path: Path) -> None:
    """Read ``path``: a cloud, or one InputError line naming the file, within
    CASE_SECONDS and CASE_BYTES of traced memory."""
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings(), capped_address_space():
            warnings.simplefilter("ignore", InputWarning)
            warnings.simplefilter("ignore", RuntimeWarning)
            try:
                read(path)
            except InputError as exc:
                msg = str(exc)
                assert "\n" not in msg and path.name in msg, msg
                assert "not enough memory" not in msg, msg
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    elapsed = time.perf_counter() - t0
    assert elapsed < CASE_SECONDS, f"{path.name}: {elapsed:.1f} s"
    assert peak < CASE_BYTES, f"{path.name}: {peak / 2**20:.0f} MB traced"


# ------------------------------------------------------------------- LAS / LAZ
def _las_bytes(compress: bool, version: str = "1.2") -> bytes:
    import io
    import laspy
    h = laspy.LasHeader(point_format=3 if version == "1.2" else 6, version=version)
    h.scales, h.offsets = [0.01] * 3, [0.0] * 3
    las = laspy.LasData(h)
    rng = np.random.default_rng(0)
    for d in "XYZ":
        las[d] = rng.integers(0, 1000, 40)
    buf = io.BytesIO()
    las.write(buf, do_compress=compress, laz_backend=laspy.LazBackend.Lazrs if compress else None)
    return buf.getvalue()


#: (offset, struct format) of the LAS header fields a hostile file lies in
_LAS_FIELDS = [(24, "B"), (25, "B"), (94, "H"), (96, "I"), (100, "I"), (104, "B"), (105, "H"),
               (107, "I"), (131, "d"), (139, "d"), (147, "d"), (155, "d"), (163, "d"), (171, "d"),
               # LAS 1.4: first extended record, their number, the 64-bit point count
               (235, "Q"), (243, "I"), (247, "Q")]


def _field_value(fmt):
    if fmt == "d":
        return st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                         st.sampled_from([0.0, 1e-300, 1e300, -0.01, 5e-13]))
    bits = struct.calcsize(fmt) * 8
    return st.one_of(st.integers(0, 2**bits - 1), st.sampled_from([0, 1, 2**bits - 1]))


las_edits = st.lists(st.sampled_from(range(len(_LAS_FIELDS))).flatmap(
    lambda i: st.tuples(st.just(i), _field_value(_LAS_FIELDS[i][1]))), min_size=1, max_size=4)


@pytest.mark.parametrize("ext,version", [(".las", "1.2"), (".laz", "1.2"), (".las", "1.4")])
@FUZZ
@given(edits=las_edits, cut=st.one_of(st.none(), st.integers(0, 2000)), tail=st.binary(max_size=64))
def test_las_with_lying_header_fields_is_read_or_refused_in_bounds(workdir, ext, version, edits, cut, tail):
    data = bytearray(_las_cache(ext == ".laz", version))
    for i, value in edits:
        off, fmt = _LAS_FIELDS[i]
        struct.pack_into("<" + fmt, data, off, value)
    data = bytes(data[:cut] if cut is not None else data) + tail
    path = workdir / f"fuzz{ext}"
    path.write_bytes(data)
    read_bounded(path)


@pytest.mark.parametrize("ext", [".las", ".laz"])
@FUZZ
@given(patches=st.lists(st.tuples(st.integers(227, 2000), st.binary(min_size=1, max_size=8)),
                        min_size=1, max_size=4), cut=st.one_of(st.none(), st.integers(227, 2000)))
def test_las_with_damaged_records_or_chunks_is_read_or_refused_in_bounds(workdir, ext, patches, cut):
    """Damaged VLRs, point records, LAZ chunks and chunk tables: a damaged
    chunk count made lazrs abort the process (a failed 21 GB allocation), a
    damaged chunk a Rust panic (a BaseException)."""
    data = bytearray(_las_cache(ext == ".laz"))
    for pos, raw in patches:
        pos %= len(data)
        data[pos:pos + len(raw)] = raw
    path = workdir / f"damaged{ext}"
    path.write_bytes(bytes(data[:cut] if cut is not None else data))
    read_bounded(path)


@FUZZ
@given(body=st.binary(min_size=0, max_size=600))
def test_lasf_followed_by_random_bytes_is_refused_in_bounds(workdir, body):
    """'LASF' and random bytes made laspy allocate without end (2.7 GB at 120 s)."""
    path = workdir / "random.las"
    path.write_bytes(b"LASF" + body)
    read_bounded(path)


_LAS_CACHE: dict = {}


def _las_cache(compress: bool, version: str = "1.2") -> bytes:
    if (compress, version) not in _LAS_CACHE:
        _LAS_CACHE[compress, version] = _las_bytes(compress, version)
    return _LAS_CACHE[compress, version]


# ------------------------------------------------------------------------- PCD
_PCD_NAMES = ["x", "y", "z", "rgb", "normal_x", "normal_y", "normal_z", "intensity", "_", "x", "label"]
pcd_field = st.tuples(st.sampled_from(_PCD_NAMES), st.sampled_from(["1", "2", "4", "8", "3", "-4", "a"]),
                      st.sampled_from(["F", "I", "U", "Q"]),
                      st.one_of(st.sampled_from(["1", "3", "0", "-1"]), st.integers(0, 10**12).map(str)))


xyz_field = st.tuples(st.sampled_from(["x", "y", "z"]), st.sampled_from(["4", "8", "2"]),
                     st.sampled_from(["F", "I"]), st.sampled_from(["1", "1", "1", "3", "0"]))


@FUZZ
@given(fields=st.tuples(st.lists(xyz_field, min_size=2, max_size=4), st.lists(pcd_field, max_size=4))
       .map(lambda parts: parts[0] + parts[1]),
       points=st.one_of(st.integers(-5, 50), st.integers(0, 10**18)).map(str),
       data=st.sampled_from(["ascii", "binary", "binary_compressed", "other", ""]),
       drop=st.sets(st.sampled_from(["FIELDS", "SIZE", "TYPE", "COUNT", "POINTS"]), max_size=2),
       body=st.one_of(st.binary(max_size=400),
                      st.lists(st.lists(st.sampled_from(["0", "1.5", "-2", "nan", "inf", "1e300", "x", "255"]),
                                        max_size=8).map(" ".join), max_size=30)
                      .map(lambda rows: ("\n".join(rows) + "\n").encode())))
def test_pcd_with_random_header_and_body_is_read_or_refused_in_bounds(workdir, fields, points, data,
                                                                      drop, body):
    lines = {"FIELDS": " ".join(f[0] for f in fields), "SIZE": " ".join(f[1] for f in fields),
             "TYPE": " ".join(f[2] for f in fields), "COUNT": " ".join(f[3] for f in fields),
             "POINTS": points}
    head = "VERSION 0.7\n" + "".join(f"{k} {v}\n" for k, v in lines.items() if k not in drop)
    path = workdir / "fuzz.pcd"
    path.write_bytes((head + f"DATA {data}\n").encode() + body)
    read_bounded(path)


# ------------------------------------------------------------------------- PLY
_PLY_TYPES = ["char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int64", "float32"]
ply_prop = st.tuples(st.sampled_from(["x", "y", "z", "nx", "ny", "nz", "radius", "red", "ux", "vz", "x"]),
                     st.sampled_from(_PLY_TYPES))


@FUZZ
@given(fmt=st.sampled_from(["ascii", "binary_little_endian", "binary_big_endian", "binary"]),
       count=st.one_of(st.integers(-2, 40), st.integers(0, 10**15)),
       props=st.lists(ply_prop, max_size=7),
       faces=st.one_of(st.none(), st.integers(0, 10**12)),
       body=st.one_of(st.binary(max_size=500),
                      st.lists(st.lists(st.sampled_from(["0", "1", "-3.5", "nan", "1e300", "3", "q"]),
                                        max_size=8).map(" ".join), max_size=30)
                      .map(lambda rows: ("\n".join(rows) + "\n").encode())))
def test_ply_with_random_header_and_body_is_read_or_refused_in_bounds(workdir, fmt, count, props, faces,
                                                                      body):
    head = f"ply\nformat {fmt} 1.0\nelement vertex {count}\n"
    head += "".join(f"property {t} {n}\n" for n, t in props)
    if faces is not None:
        head += f"element face {faces}\nproperty list uchar int vertex_indices\n"
    path = workdir / "fuzz.ply"
    path.write_bytes((head + "end_header\n").encode() + body)
    read_bounded(path)


# ----------------------------------------------------------- XYZ / PTS / OFF
text_rows = st.lists(st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True).map(repr),
                                        st.sampled_from(["1e400", "x", "#", "0", "3", "-1"])),
                              max_size=8).map(" ".join), max_size=40)


@pytest.mark.parametrize("ext,first", [(".xyz", ""), (".pts", ""), (".off", "OFF\n")])
@FUZZ
@given(rows=text_rows)
def test_text_formats_with_random_rows_are_read_or_refused_in_bounds(workdir, ext, first, rows):
    path = workdir / f"fuzz{ext}"
    path.write_text(first + "\n".join(rows) + "\n")
    read_bounded(path)


# ------------------------------------------------------------------------- E57
@FUZZ
@given(body=st.binary(max_size=2000), prefix=st.sampled_from([b"ASTM-E57", b""]))
def test_e57_random_bytes_are_refused_in_bounds(workdir, body, prefix):
    path = workdir / "fuzz.e57"
    path.write_bytes(prefix + body)
    read_bounded(path)
