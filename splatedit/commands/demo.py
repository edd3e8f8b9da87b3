"""The headless demo: the paper's Bunny edit (Fig. 6) on the bundled model.

Bends the bunny's tall ear, then lifts and tilts its head, writing the result next to
the user: ``bunny-demo.ply`` (the deformed splats), ``bunny-demo.json`` (the
edit script, replayable with ``splatedit deform``) and, when a Vulkan device
is present, ``bunny-before.png`` / ``bunny-demo.png``.
"""

from __future__ import annotations

import time
from pathlib import Path

from splatedit.errors import InputError
from splatedit.script import parse_script

#: The demo's edit script, in model coordinates of the bundled bunny
#: (bounding box about [-0.5, 0.5]^3, y up).
DEMO_SCRIPT = {
    "version": 1,
    "solver": {"method": "auto"},
    "edits": [
        {   # bend the tall ear backwards about its base
            "support": {"sphere": {"center": [-0.07, 0.37, -0.05], "radius": 0.2}},
            "handle": {"sphere": {"center": [0.0, 0.47, -0.1], "radius": 0.06}},
            "transform": {"rotate": {"axis": [0, 0, 1], "degrees": -40, "center": [-0.15, 0.26, 0.0]}},
        },
        {   # lift the head (with both ears) and tilt it back
            "support": {"box": {"min": [-0.55, -0.08, -0.45], "max": [0.2, 0.55, 0.45]}},
            "handle": {"box": {"min": [-0.55, 0.14, -0.45], "max": [0.06, 0.55, 0.45]}},
            "transform": {"translate": [0.0, 0.04, 0.0], "rotate": {"axis": [0, 0, 1], "degrees": -10}},
        },
    ],
}


def run_demo(output_dir: Path, *, progress=None, log=print, render: bool = True, overwrite: bool = False) -> Path:
    """Run the demo edit; return the path of the deformed PLY."""
    from splatedit.data import default_model_path
    from splatedit.io import read, write
    from splatedit.atomic import check_writable_target
    from splatedit.script import run_script

    if output_dir.exists() and not output_dir.is_dir():
        raise InputError("is not a directory (demo -o names the folder for its results)",
                         path=str(output_dir))
    try:
        output_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:     # under a file, read-only, name too long
        raise InputError(f"cannot create the output folder: {exc.strerror or exc}",
                         path=str(output_dir)) from None
    out_ply = output_dir / "bunny-demo.ply"
    out_json = output_dir / "bunny-demo.json"
    for p in (out_ply, out_json):
        check_writable_target(p, overwrite=overwrite)
    src = default_model_path()
    cloud = read(src, progress=progress)
    log(f"loaded the bundled Stanford bunny: {cloud.n} splats ({src})")
    script = parse_script(DEMO_SCRIPT, source="demo script")
    t0 = time.perf_counter()

    def on_edit(rep):
        if hasattr(progress, "close"):
            progress.close()
        log(rep.line())

    deformed, _ = run_script(cloud, script, progress=progress, on_edit=on_edit)
    log(f"deformed in {time.perf_counter() - t0:.2f} s")
    write(out_ply, deformed, overwrite=overwrite)
    script.save(out_json)
    log(f"wrote {out_ply} and {out_json} (replay: splatedit deform {src} --edit {out_json} -o OUT.ply)")
    if render:
        from splatedit.render.camera import Camera
        from splatedit.render.splat.headless import render_to_png
        from splatedit.render.vk import VulkanError
        size = (960, 720)
        from splatedit.model.extent import framing_extent
        ext = framing_extent(cloud.positions)
        # the same three-quarter view for both images, framed on the original model's main body
        camera = Camera.frame(ext.lo, ext.hi, aspect=size[0] / size[1], direction=(-0.45, 0.25, 1.0))
        try:
            for cl, name in ((cloud, "bunny-before.png"), (deformed, "bunny-demo.png")):
                target = output_dir / name
                check_writable_target(target, overwrite=overwrite)
                render_to_png(cl, target, size=size, camera=camera)
                log(f"wrote {target}")
        except VulkanError as exc:  # no Vulkan driver/device: the edit itself still succeeded
            log(f"skipped the PNG renders (no usable Vulkan device): {exc}")
    return out_ply
