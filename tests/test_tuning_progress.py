"""Long calls show progress, stop on Ctrl-C and validate before starting work (issue 50, item 12).

tradeoff(CoatedDiffuse(...)) ran 690 s in silence with the default measure=True; fit_many with a
typo in params started a Dask cluster and then failed every target with the same error."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.tuning import costs


@pytest.mark.filterwarnings("ignore:tradeoff. live timings are noisy:RuntimeWarning")
def test_tradeoff_reports_progress_for_every_stage():
    seen = []
    t = bk.tradeoff(bk.Conductor.from_metal("Cu", alpha=0.3), n=256, n_albedo=256, n_timing=1024, repeats=1,
                    progress=lambda done, total, stage: seen.append((done, total, stage)))
    stages = sorted({s for _, _, s in seen})
    assert stages == ["errors of configuration", "timing configuration"]
    for st in stages:
        steps = [(d, tot) for d, tot, s in seen if s == st]
        assert [d for d, _ in steps] == list(range(1, len(t) + 1)) and all(tot == len(t) for _, tot in steps)


def test_ctrl_c_stops_between_configurations():
    calls = []

    def interrupt(done, total, stage):
        calls.append(done)
        if done == 3:
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        bk.tradeoff(bk.Conductor.from_metal("Cu", alpha=0.3), n=256, n_albedo=256, measure=False, progress=interrupt)
    assert calls == [1, 2, 3]          # nothing ran after the interrupt
    with pytest.raises(KeyboardInterrupt):
        bk.simplify(bk.Conductor.from_metal("Cu", alpha=0.3), 1e-3, n=256, n_albedo=256, progress=interrupt)


def test_progress_argument_is_checked():
    with pytest.raises(TypeError, match="progress"):
        bk.tradeoff(bk.Diffuse(0.5), measure=False, progress="yes")


def test_default_timing_size_keeps_within_the_budget():
    """The default n_timing shrinks when one reference call times the whole table beyond the
    budget (CoatedDiffuse: 340 configurations of 64-walk evaluations), never below 64 pairs,
    and stays when the table is cheap. (Extreme budgets only: the figure in between depends on
    the machine's speed; the wall time itself is measured in the report, not asserted.)"""
    model = bk.CoatedDiffuse(0.6, alpha=0.1)
    from bsdfkit.tuning.configs import configurations
    cfgs = configurations(model)
    assert len(cfgs) > 100
    assert costs._budgeted_n_timing(cfgs, "eval", 4096, 5, 1, 0, budget=1e-6) == costs.MIN_AUTO_TIMING
    assert costs._budgeted_n_timing(cfgs, "eval", 4096, 5, 1, 0, budget=1e9) == 4096


def test_fit_many_checks_its_arguments_before_starting_a_cluster(monkeypatch):
    import distributed

    def no_cluster(*a, **k):
        raise AssertionError("a cluster was started")
    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    targets = [bk.Conductor.from_metal("Cu", alpha=0.2)] * 2
    with pytest.raises(ValueError, match="params: 'alpah' is not a differentiable parameter of Conductor"):
        bk.fitting.fit_many(targets, bk.Conductor, params=("alpah",))
    with pytest.raises(ValueError, match="loss"):
        bk.fitting.fit_many(targets, bk.Conductor, loss="l1")
