"""Distortion figures of the live pose, computed off the UI thread.

A drag never waits for them: one background job per pose, one at a time
(``on_change`` is called when it is done); the figures shown may be those of
the pose one job earlier.  A :class:`~splatedit.deform.distortion.
DistortionProbe` is built once per (basis, cloud); then about 5 ms per 100k
support splats (docs/PERFORMANCE.md).  ``sync`` computes at once (tests).
"""

from __future__ import annotations

from splatedit.app.document.jobs import Job


class DistortionFeed:
    def __init__(self, on_change, *, sync: bool = False):
        self.on_change = on_change
        self.sync = sync
        self._src = None          # (basis, cloud) of the probe
        self._probe = None
        self._job: Job | None = None
        self._result = None       # (dC bytes, DistortionStats)

    def stats(self, basis, cloud, dc):
        """The stats of displacement ``dc`` ((k, 3) float64, or a
        RotationDisplacement) of ``basis`` on ``cloud``, or None until the first
        figures are ready."""
        from splatedit.deform.distortion import DistortionProbe, basis_distortion
        from splatedit.deform.rotation import split_displacement
        if self._src is None or self._src[0] is not basis or self._src[1] is not cloud:
            if self._job is not None:
                self._job.cancel.set()
            self._src, self._probe, self._job, self._result = (basis, cloud), None, None, None
        job = self._job
        if job is not None and job.done:
            self._job = None
            if job.error is None:
                self._result = job.result
        key = dc.tobytes()
        if self._job is None and (self._result is None or self._result[0] != key):
            d0, rot = split_displacement(dc)

            def work(progress):
                if hasattr(basis, "detail_for_gpu"):   # a DetailBasis: its own exact figures
                    return key, basis.distortion(cloud, dc)
                if rot is not None or getattr(dc, "curves", ()):   # exact Jacobians: rotations, curve frames
                    return key, basis_distortion(basis, cloud, dc)
                if self._probe is None:
                    self._probe = DistortionProbe(basis, cloud)
                return key, self._probe.stats(d0)
            self._job = Job("distortion", work, self.on_change, sync=self.sync)
            if self._job.done:
                return self.stats(basis, cloud, dc)
        return None if self._result is None else self._result[1]
