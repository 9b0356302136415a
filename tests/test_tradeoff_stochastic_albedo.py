"""albedo_err of stochastic (layered) models, against albedo() (issue 50, item 2).

The layered walks' ``sample().pdf`` is only proportional to the density (``pdf_is_proportional``):
dividing other configurations' f by it gave "albedo errors" of 400 to 43,622 for materials whose
albedo is ~0.6. Each reported albedo_err must equal, within Monte Carlo error, the largest
difference of the configuration's albedo() from the converged reference's albedo() on the same wo.
"""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.tuning.errors import _converged

N_MC = 1 << 16


@pytest.mark.parametrize("model", [bk.CoatedDiffuse(0.6, alpha=0.1),
                                   bk.CoatedConductor.from_metal("Au", interface_alpha=0.1)], ids=repr)
def test_albedo_err_equals_the_albedo_difference(model):
    t = bk.tradeoff(model, measure=False, n=64)
    wo = t.directions.albedo_wo
    ref = _converged(t.reference)                    # n_samples 256, max_depth 100: the documented reference
    a_ref = ref.albedo(wo, n_samples=N_MC, seed=5)
    assert np.all(t["albedo_err"] <= np.max(a_ref))  # an albedo difference cannot exceed the albedos involved
    # one configuration per setting that changes the expected albedo (max_depth, masking, method),
    # plus the most accurate one (its error is Monte Carlo noise only)
    seen, rows = set(), []
    for i, c in enumerate(t.configs):
        key = (c.labels.get("max_depth"), c.labels.get("masking"), c.labels.get("method"))
        if c.dtype is np.float64 and key not in seen:
            seen.add(key)
            rows.append(i)
    assert len(rows) >= 6
    for i in rows:
        a = t.configs[i].model.albedo(wo, n_samples=N_MC, seed=9)
        want = float(np.abs(a - a_ref).max())
        assert t[i]["albedo_err"] == pytest.approx(want, abs=0.03), t[i]["config"]
    # and the truncated walk's large, real loss is reported as such
    one = next(i for i in rows if t.configs[i].labels.get("max_depth") == "1")
    assert t[one]["albedo_err"] > 0.2


def test_simplify_albedo_metric_of_a_layered_model():
    """metric="albedo" picks a configuration whose albedo() is within tol of the input's."""
    model = bk.CoatedDiffuse(0.6, alpha=0.1)
    m, rep = bk.simplify(model, 0.05, metric="albedo", n=64)
    assert rep.error["albedo"] <= 0.05
    wo = bk.direction(theta=np.radians([0.0, 45.0, 80.0]), phi=0.0)
    diff = np.abs(m.albedo(wo.astype(rep.dtype), N_MC, seed=2) - _converged(model).albedo(wo, N_MC, seed=3)).max()
    assert diff <= 0.05 + 0.02
