"""Monte Carlo convergence of the preview renderer: the error against a high-spp render falls
like 1 / sqrt(spp) (the fitted log-log slope is -1/2), i.e. the estimator is unbiased with
finite variance and the samples of a pixel are independent."""
import math

import numpy as np

import bsdfkit as bk
from bsdfkit import render as R

RES = 32
REF_SPP = 4096
SPPS = (4, 16, 64, 256)
SEEDS = (1, 2, 3)


def test_error_falls_like_inverse_sqrt_spp():
    # rough gold on the checkerboard under the procedural sky (sun included): MIS of the
    # environment sampler and the GGX sampler, ground interreflections, Russian roulette
    scene = R.default_scene(bk.Conductor.from_metal("Au", alpha=0.25))
    scene.look_at((0.0, 1.3, 3.6), (0.0, 0.9, 0.0), fov=40)
    kw = dict(width=RES, height=RES, max_depth=6, progress=False)
    ref = R.render(scene, spp=REF_SPP, seed=1000, **kw).astype(np.float64)
    rmse = []
    for spp in SPPS:
        errs = [np.mean((R.render(scene, spp=spp, seed=s, **kw) - ref) ** 2) for s in SEEDS]
        rmse.append(math.sqrt(np.mean(errs)))
    slope, _ = np.polyfit(np.log(SPPS), np.log(rmse), 1)
    print("spp", SPPS, "rmse", [f"{e:.4g}" for e in rmse], f"slope {slope:.3f}")
    # reference noise (1/16 of the variance at 256 spp) flattens the slope by ~0.01
    assert -0.6 < slope < -0.42, (slope, rmse)
    # every step of 4x in spp halves the error (within the scatter of 3 seeds)
    ratios = np.array(rmse[:-1]) / np.array(rmse[1:])
    assert np.all((ratios > 1.5) & (ratios < 2.7)), ratios
