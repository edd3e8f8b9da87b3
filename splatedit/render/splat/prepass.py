"""The splat renderer's compute pre-pass (``prepare*.comp``) and its windows.

Once per frame the pre-pass does the per-splat work (deformation, culling,
screen setup) and writes compact records that both splat passes draw
indirectly with the fetch-only ``prepared.vert``.  A cloud whose records or
geometry exceed one storage binding is prepared and drawn in windows of
``RENDER_PREPASS_WINDOW_SPLATS`` splats; a basis larger than one binding is
bound in several descriptor sets (one dispatch each).

:class:`Prepass` is owned by :class:`splatedit.render.splat.renderer.Renderer`
(``renderer.prepass_part``); it reads the scene's buffers from the renderer's
:class:`~splatedit.render.splat.uploads.SceneUploads` and builds its pipelines in
the renderer's pipeline cache.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.splat.layout import (GEOM_STRIDE, PREP_MAX_SIZE, PREP_SET, PREP_SET_DETAIL, REC_A_BYTES,
                                           REC_B_BYTES, WORKGROUP, rp_window, splat_desc)
from splatedit.render.uniforms import PREP_PUSH, PREPARED_PUSH
from splatedit.tolerances import RENDER_PREPASS_WINDOW_SPLATS


@dataclass
class PrepObjects:
    """Buffers and descriptor sets of the compute pre-pass: one set per basis
    window inside each splat window (one splat window when the cloud fits one
    storage binding)."""

    objects: list            # every Vulkan object above, destroyed in reverse
    dset: V.DescriptorSet    # the first window's first set (the draws' set)
    rec_a: V.Buffer          # records A, 48 bytes per splat of the largest window
    rec_b: V.Buffer          # records B, 32 bytes per splat
    draws: V.Buffer          # two indirect draws (quads, points)
    #: per splat window: (first splat, count, [(descriptor set, first splat, count)])
    windows: list


class Prepass:
    """The compute pre-pass of a :class:`~splatedit.render.splat.renderer.Renderer`:
    its buffers and descriptor sets (:attr:`current`, a :class:`PrepObjects`
    or None; built on first use by :meth:`objects`, dropped by :meth:`free`
    whenever a buffer they bind changes), its windows and its recording.

    Args:
        dev: the renderer's :class:`splatedit.render.vk.Device`.
        cache: the renderer's pipeline cache.
        scene: the renderer's :class:`~splatedit.render.splat.uploads.SceneUploads`.
        ubo, dC_ubo: the frame uniforms and deform.glsl's displacement block.
    """

    def __init__(self, dev, cache, scene, ubo, dC_ubo):
        self.dev, self.cache, self.scene = dev, cache, scene
        self.ubo, self.dC_ubo = ubo, dC_ubo
        #: the built buffers and sets (None until :meth:`objects`)
        self.current: PrepObjects | None = None

    def free(self):
        """Destroy the buffers and sets (rebuilt by the next :meth:`objects`)."""
        if self.current is not None:
            for obj in reversed(self.current.objects):
                obj.destroy()
            self.current = None

    def spans(self) -> list[tuple[int, int]]:
        """(first splat, splat count) windows of the pre-pass: the whole cloud
        when its records and per-splat arrays fit one storage binding (up to
        2,796,202 splats with lavapipe's 128 MiB), else windows of
        RENDER_PREPASS_WINDOW_SPLATS (or fewer where the device limit is
        smaller), each prepared and drawn in turn."""
        limit = int(self.dev.limits.maxStorageBufferRange)
        per_splat = max(REC_A_BYTES, GEOM_STRIDE, 16 if self.scene.detail_buf is not None else 0)
        if self.scene.n * per_splat <= limit:
            return [(0, self.scene.n)]
        align = max(int(self.dev.limits.minStorageBufferOffsetAlignment), 1)
        per = min(RENDER_PREPASS_WINDOW_SPLATS, limit // per_splat) // WORKGROUP * WORKGROUP
        while per > WORKGROUP and (per * 4) % align:       # 4: the smallest per-splat stride
            per -= WORKGROUP
        per = max(per, WORKGROUP)
        return [(b, min(per, self.scene.n - b)) for b in range(0, self.scene.n, per)]

    def basis_chunks(self, basis, first: int = 0, count: int | None = None) -> list[tuple[int, int, int, int]]:
        """(first splat, splat count, byte offset, byte range) windows of the
        basis buffer that each fit one storage binding, covering splats
        first .. first + count - 1 (all by default)."""
        count = self.scene.n - first if count is None else count
        row_bytes = 64 * self.scene.basis_groups
        if basis.size < self.scene.n * row_bytes:          # the dummy (nothing deformed): one window
            return [(first, count, 0, basis.size)]
        limit = int(self.dev.limits.maxStorageBufferRange)
        align = max(int(self.dev.limits.minStorageBufferOffsetAlignment), 1)
        per = max(limit // row_bytes // WORKGROUP * WORKGROUP, WORKGROUP)
        while (per * row_bytes) % align:
            per -= WORKGROUP
        out = []
        for base in range(first, first + count, per):
            cnt = min(per, first + count - base)
            out.append((base, cnt, base * row_bytes, cnt * row_bytes))
        return out

    def objects(self) -> PrepObjects:
        """The pre-pass buffers and descriptor sets for the current scene (built
        on first use, kept until :meth:`free`)."""
        if self.current is None:
            objs = []
            try:
                spans = self.spans()
                slots = max(cnt for _, cnt in spans)
                rec_a = V.Buffer(self.dev, slots * REC_A_BYTES, ("storage",))
                objs.append(rec_a)
                rec_b = V.Buffer(self.dev, slots * REC_B_BYTES, ("storage",))
                objs.append(rec_b)
                draws = V.Buffer(self.dev, 32, ("storage", "indirect"))
                objs.append(draws)
                basis = self.scene.basis_binding()
                windowed = len(spans) > 1
                windows = []
                for w0, wn in spans:
                    chunks = self._sets(objs, (rec_a, rec_b, draws), basis, w0, wn, w0, wn, windowed)
                    windows.append((w0, wn, chunks))
            except BaseException:
                for o in reversed(objs):
                    o.destroy()
                raise
            self.current = PrepObjects(objs, windows[0][2][0][0], rec_a, rec_b, draws, windows)
        return self.current

    def _sets(self, objs: list, records: tuple, basis, w0: int, wn: int, first: int, count: int,
              windowed: bool) -> list:
        """Descriptor sets (appended to ``objs``) that prepare splats ``first`` ..
        ``first + count - 1`` of splat window (w0, wn) into ``records`` (records
        A, B, indirect draws): one per basis window, as (set, first splat, count)."""
        detail = self.scene.detail_buf

        def span(buf, stride):
            return (buf, w0 * stride, wn * stride) if windowed else buf
        rec_a, rec_b, draws = records
        sets = []
        for base, cnt, off, rng in self.basis_chunks(basis, first, count):
            dset = V.DescriptorSet(self.dev, self.cache.set_layout(PREP_SET if detail is None else PREP_SET_DETAIL))
            objs.append(dset)
            writes = {0: self.ubo, 1: span(self.scene.geom, GEOM_STRIDE), 2: span(self.scene.color, 4),
                      3: span(self.scene.flags, 4), 4: (basis, off, rng),
                      5: rec_a, 6: rec_b, 7: draws, 8: self.dC_ubo}
            if detail is not None:
                writes[9] = span(detail, 16)
            dset.write(writes)
            sets.append((dset, base, cnt))
        return sets

    def range_sets(self, first: int, count: int) -> tuple[int, list, list]:
        """Descriptor sets that prepare only splats ``first`` .. ``first + count - 1``
        (inside one splat window; ``first`` a multiple of the workgroup size):
        (window index, [(set, first splat, count)], the sets to destroy).
        :mod:`splatedit.render.splat.progressive` draws its chunks so."""
        prep = self.objects()
        k = next(i for i, (w0, wn, _) in enumerate(prep.windows) if w0 <= first < w0 + wn)
        w0, wn, _ = prep.windows[k]
        if first % WORKGROUP or first + count > w0 + wn:
            raise ParameterError("chunk", f"splats {first}..{first + count - 1} do not start a workgroup "
                                          f"inside pre-pass window {w0}..{w0 + wn - 1}")
        objs = []
        try:
            sets = self._sets(objs, (prep.rec_a, prep.rec_b, prep.draws), self.scene.basis_binding(), w0, wn,
                              first, count, len(prep.windows) > 1)
        except BaseException:
            for o in reversed(objs):
                o.destroy()
            raise
        return k, sets, objs

    def record(self, cb, window: int = 0, sets: list | None = None):
        """Compute pre-pass of splat window ``window``: records + indirect draw
        counts for this frame's camera (one dispatch per basis window); only
        the splats of ``sets`` (from :meth:`range_sets`) when given. Before
        any window but the first of a frame, it waits for the draws that read
        the previous window's records."""
        prep = self.objects()
        w0, wn, chunks = prep.windows[window]
        partial = sets is not None
        chunks = sets if partial else chunks
        g = self.scene.basis_groups
        detail = self.scene.detail_buf is not None
        stem = "prepare_detail" if detail else "prepare"
        comp = f"{stem}.comp" if g == 1 else f"{stem}_k{4 * g}.comp"
        layout = V.LayoutDesc(sets=(PREP_SET_DETAIL if detail else PREP_SET,), push_bytes=PREP_PUSH.itemsize,
                              push_stages="comp")
        pipe = self.cache.pipeline(V.ComputeDesc(comp, layout))
        if len(prep.windows) > 1 or partial:     # earlier draws read records and counts
            cb.memory_barrier("draw_indirect|vertex", "indirect_read|shader_read", "transfer|compute",
                              "transfer_write|shader_write")
        cb.fill_buffer(prep.draws, 0)
        if partial:     # the shader sets the vertex counts at the window's first splat only
            cb.fill_buffer(prep.draws, 4, 0, 4)
            cb.fill_buffer(prep.draws, 1, 16, 4)
        cb.memory_barrier("transfer", "transfer_write", "compute", "shader_read|shader_write")
        cb.bind_pipeline(pipe)
        for j, (dset, base, cnt) in enumerate(chunks):
            if j:
                cb.memory_barrier("compute", "shader_write", "compute", "shader_read|shader_write")
            cb.bind_descriptor_set(pipe, dset)
            cb.push_constants(pipe, np.array((base, cnt, wn, w0), PREP_PUSH))
            cb.dispatch((cnt + WORKGROUP - 1) // WORKGROUP)
        cb.memory_barrier("compute", "shader_write", "draw_indirect|vertex",
                          "indirect_read|shader_read")

    def draw_pipeline(self, kind: str, mode: int, accum_format: str):
        """The pipeline that draws the records of a splat pass ``kind`` with
        ``prepared.vert`` (``mode`` 1 quads, 2 points) into ``accum_format`` targets."""
        layout = V.LayoutDesc(sets=(PREP_SET if self.scene.detail_buf is None else PREP_SET_DETAIL,),
                              push_bytes=PREPARED_PUSH.itemsize, push_stages="vert")
        return self.cache.pipeline(splat_desc("prepared.vert", kind, accum_format, layout, spec=((0, mode),),
                                               topology="point_list" if mode == 2 else "triangle_strip"))

    def window_count(self, prepared: bool) -> int:
        """Pre-pass windows of this frame (1 for the vertex path)."""
        return len(self.objects().windows) if prepared else 1
