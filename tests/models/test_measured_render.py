"""Measured models in the preview renderer: a MERL table and a tensor file made from a conductor
render like the conductor itself (same scene, seed and sample count)."""
import numpy as np

import bsdfkit as bk


def test_measured_models_render_like_their_source(tmp_path):
    src = bk.Conductor.from_metal("Cu", alpha=0.3)
    merl = bk.MERL(bk.measured.write_merl(tmp_path / "cu.binary", src), interpolation="linear")
    tab = bk.measured.tabulate(src, resolution=32)
    kw = dict(width=48, height=48, spp=32, max_depth=3, seed=1, progress=False)
    ref = bk.render.preview(src, **kw)
    for m in (merl, tab, bk.Measured.load(tab.save(tmp_path / "cu_rgb.bsdf"))):
        img = bk.render.preview(m, **kw)
        assert img.shape == ref.shape and np.all(np.isfinite(img))
        # the sphere's mean radiance agrees to a few percent (noise and tabulation error)
        rel = abs(img.mean() - ref.mean()) / ref.mean()
        assert rel < 0.05, (m, rel)
        assert np.median(np.abs(img - ref)) < 0.1 * np.median(ref)
