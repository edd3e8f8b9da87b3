"""A synthetic airborne-LiDAR-like scan of any size, generated tile by tile
(the same points on every pass, in bounded memory): rolling terrain, flat-
and gable-roofed buildings with walls, trees (noisy crowns) and a little
scattered noise.  Used by ``scripts/make_big_scan.py`` (a 10^8-point COPC
file for the out-of-core measurements) and by ``bench outofcore`` (a small
one).

Units: metres; the scan covers a square of ``side`` metres at a density of
``n / side**2`` points per square metre (``side`` defaults to 25 points per
square metre), placed at UTM-like coordinates (500,000, 5,000,000).
Points are LAS point format 7 records (:func:`splatedit.io.copc.record_dtype`)
on a millimetre grid.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numpy as np

from splatedit.io.copc import record_dtype

ORIGIN = np.array([500_000.0, 5_000_000.0, 0.0])
SCALE = np.array([0.001, 0.001, 0.001])
#: building lots (m): one building at most per lot
_LOT = 60.0
#: tree lots (m)
_TREE_LOT = 22.0


@dataclass
class Terrain:
    """The scan's parameters (see the module docstring).

    Attributes:
        n: points.
        side: the square's side (m).
        tiles: tiles per side (``tiles**2`` chunks of about ``n / tiles**2``).
        seed: everything random derives from it.
    """
    n: int
    side: float
    tiles: int
    seed: int = 0

    @classmethod
    def of(cls, n: int, *, density: float = 25.0, chunk_points: int = 2_000_000, seed: int = 0) -> "Terrain":
        """The terrain of ``n`` points at ``density`` points per square
        metre, in tiles of about ``chunk_points``."""
        side = float(np.sqrt(n / density))
        tiles = max(1, int(np.ceil(np.sqrt(n / chunk_points))))
        return cls(n, side, tiles, seed)

    @property
    def offset(self) -> np.ndarray:
        """(3,) the LAS offset: the square's centre at height 0."""
        return ORIGIN + [self.side / 2, self.side / 2, 0.0]

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """A box (file units) holding every point."""
        return ORIGIN + [0, 0, -5.0], ORIGIN + [self.side, self.side, 80.0]

    def ground(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Ground height (m) at local ``x, y`` (m)."""
        return (6 * np.sin(x / 97.0) * np.cos(y / 131.0) + 3 * np.sin((x + 2 * y) / 53.0)
                + 0.004 * x + 10.0)

    def _buildings(self):
        """Per lot (gx, gy): (present, x0, y0, w, d, height, gable)."""
        lots = int(np.ceil(self.side / _LOT))
        r = np.random.default_rng([self.seed, 1])
        present = r.random((lots, lots)) < 0.45
        w = r.uniform(10, 35, (lots, lots))
        d = r.uniform(10, 35, (lots, lots))
        x0 = np.arange(lots)[:, None] * _LOT + r.uniform(2, _LOT - 2 - w)
        y0 = np.arange(lots)[None, :] * _LOT + r.uniform(2, _LOT - 2 - d)
        h = r.uniform(5, 30, (lots, lots))
        gable = r.random((lots, lots)) < 0.4
        present &= (x0 + w < self.side) & (y0 + d < self.side)      # inside the square
        return present, x0, y0, w, d, h, gable

    def _footprint(self, x, y, b):
        present, x0, y0, w, d, h, gable = b
        lots = present.shape[0]
        gx = np.clip((x // _LOT).astype(np.int64), 0, lots - 1)
        gy = np.clip((y // _LOT).astype(np.int64), 0, lots - 1)
        inside = (present[gx, gy] & (x >= x0[gx, gy]) & (x < x0[gx, gy] + w[gx, gy])
                  & (y >= y0[gx, gy]) & (y < y0[gx, gy] + d[gx, gy]))
        return inside, gx, gy

    def _roof(self, x, y, gx, gy, b):
        present, x0, y0, w, d, h, gable = b
        base = self.ground(x0[gx, gy] + w[gx, gy] / 2, y0[gx, gy] + d[gx, gy] / 2)
        top = base + h[gx, gy]
        t = np.abs((y - y0[gx, gy]) / d[gx, gy] - 0.5)     # 0 at the ridge
        return np.where(gable[gx, gy], top + 4.0 * (0.5 - t), top)

    def tile(self, i: int) -> np.ndarray:
        """The records of tile ``i`` (0 .. tiles**2 - 1)."""
        T = self.tiles
        counts = np.full(T * T, self.n // (T * T))
        counts[: self.n - counts.sum()] += 1
        n = int(counts[i])
        r = np.random.default_rng([self.seed, 2, i])
        ts = self.side / T
        tx, ty = (i // T) * ts, (i % T) * ts
        b = self._buildings()
        kind = r.random(n)
        x = tx + r.random(n) * ts
        y = ty + r.random(n) * ts
        z = self.ground(x, y) + r.normal(0, 0.03, n)
        cls = np.full(n, 2, np.uint8)                 # ground
        inside, gx, gy = self._footprint(x, y, b)
        z = np.where(inside, self._roof(x, y, gx, gy, b) + r.normal(0, 0.02, n), z)
        cls[inside] = 6                               # building
        # walls: 8 % of the points, on the nearest lot's building outline
        wall = (kind < 0.08)
        present, x0, y0, w, d, h, gable = b
        wall &= present[gx, gy]
        k = np.flatnonzero(wall)
        if len(k):
            gxk, gyk = gx[k], gy[k]
            per = 2 * (w[gxk, gyk] + d[gxk, gyk])
            s = r.random(len(k)) * per
            ww, dd = w[gxk, gyk], d[gxk, gyk]
            px = np.where(s < ww, s, np.where(s < ww + dd, ww, np.where(s < 2 * ww + dd, 2 * ww + dd - s, 0.0)))
            py = np.where(s < ww, 0.0, np.where(s < ww + dd, s - ww, np.where(s < 2 * ww + dd, dd, per - s)))
            x[k] = x0[gxk, gyk] + px
            y[k] = y0[gxk, gyk] + py
            base = self.ground(x0[gxk, gyk] + ww / 2, y0[gxk, gyk] + dd / 2)
            z[k] = base - 2 + r.random(len(k)) * (h[gxk, gyk] + 2)
            cls[k] = 6
        # trees: 15 % of the points, in crowns around lot-jittered trunks outside buildings
        tree = (kind >= 0.08) & (kind < 0.23) & ~inside
        k = np.flatnonzero(tree)
        if len(k):
            lx = np.floor(x[k] / _TREE_LOT)
            ly = np.floor(y[k] / _TREE_LOT)
            h1 = np.sin(lx * 12.9898 + ly * 78.233 + self.seed) * 43758.5453
            jx = (h1 - np.floor(h1))
            h2 = np.sin(lx * 39.346 + ly * 11.135 + self.seed) * 24634.6345
            jy = (h2 - np.floor(h2))
            cx, cy = (lx + 0.2 + 0.6 * jx) * _TREE_LOT, (ly + 0.2 + 0.6 * jy) * _TREE_LOT
            rad = 2.5 + 2.5 * jx
            ang = r.random(len(k)) * 2 * np.pi
            rr = rad * np.sqrt(r.random(len(k)))
            x[k] = np.clip(cx + rr * np.cos(ang), tx, tx + ts)
            y[k] = np.clip(cy + rr * np.sin(ang), ty, ty + ts)
            top = 6 + 8 * jy
            z[k] = self.ground(x[k], y[k]) + top - rad * (rr / rad) ** 2 * 0.8 + r.normal(0, 0.4, len(k))
            cls[k] = 5
        # scattered noise: 0.2 %
        k = np.flatnonzero((kind >= 0.23) & (kind < 0.232))
        z[k] += r.uniform(-3, 25, len(k))
        cls[k] = 1
        rec = np.zeros(n, dtype=record_dtype(7, 36))
        off = self.offset
        rec["X"] = np.rint((x + ORIGIN[0] - off[0]) / SCALE[0])
        rec["Y"] = np.rint((y + ORIGIN[1] - off[1]) / SCALE[1])
        rec["Z"] = np.rint((z - off[2]) / SCALE[2])
        rec["classification"] = cls
        rec["returns"] = 0x11
        rec["intensity"] = np.clip(r.normal(np.where(cls == 6, 30000, np.where(cls == 5, 12000, 20000)), 3000),
                                   0, 65535).astype(np.uint16)
        rec["gps_time"] = 1.0e8 + i + r.random(n)
        palette = {2: (120, 110, 80), 6: (170, 90, 70), 5: (60, 130, 50), 1: (200, 200, 200)}
        for c, (rr_, gg, bb) in palette.items():
            m = cls == c
            shade = r.normal(1.0, 0.08, int(m.sum()))
            for nm, v in (("red", rr_), ("green", gg), ("blue", bb)):
                rec[nm][m] = np.clip(v * shade, 0, 255).astype(np.uint16) * 257
        return rec

    def chunks(self) -> Iterator[np.ndarray]:
        """Every tile's records, in order."""
        for i in range(self.tiles * self.tiles):
            yield self.tile(i)


def write_terrain_copc(path, n: int, *, seed: int = 0, laz_path=None, progress=None,
                       chunk_points: int = 2_000_000, **layout):
    """Write the terrain of ``n`` points as COPC to ``path`` (streaming) and,
    with ``laz_path``, the same points as a plain LAZ (laspy, streaming).

    Returns:
        the :class:`splatedit.io.copc.WriteReport`.
    """
    from splatedit.io.copc import build_copc
    t = Terrain.of(n, chunk_points=chunk_points, seed=seed)
    lo, hi = t.bounds
    rep = build_copc(path, t.chunks, point_format=7, scale=SCALE, offset=t.offset, mins=lo, maxs=hi,
                     progress=progress, count=n, **layout)
    if laz_path is not None:
        import laspy
        hdr = laspy.LasHeader(point_format=7, version="1.4")
        hdr.scales, hdr.offsets = SCALE, t.offset
        with laspy.open(str(laz_path), mode="w", header=hdr, do_compress=True,
                        laz_backend=laspy.LazBackend.Lazrs) as w:
            for rec in t.chunks():
                w.write_points(laspy.PackedPointRecord.from_buffer(rec.tobytes(), hdr.point_format))
    return rep
