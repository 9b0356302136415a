"""tools/perf/throughput.py's bookkeeping: merging repeated measurements of a cell and the steal share.

The script itself is a benchmark (never run in the suite); these are its pure helpers, whose
mistakes would silently change the committed table's verdicts."""
import math
import sys

import numpy as np
import pytest
from perf_support import load_tool


@pytest.fixture(scope="module")
def tp():
    return load_tool("throughput.py")


def test_merge_cells_keeps_each_variants_minimum(tp):
    a = {("hair", "eval", "float32"): {"kernel_1t": 2.0, "kernel_2t": 1.5, "mi_kernel_2t": 1.0, "stream_2t": 0.3,
                                       "busy_cores": 0.1, "steal": 0.02}}
    b = {("hair", "eval", "float32"): {"kernel_1t": 1.8, "kernel_2t": 1.6, "mi_kernel_2t": 0.9, "stream_2t": 0.4,
                                       "busy_cores": 0.25, "steal": 0.06}}
    m = tp.merge_cells(a, b)[("hair", "eval", "float32")]
    assert m["kernel_1t"] == 1.8 and m["kernel_2t"] == 1.5      # each side's own minimum
    assert m["mi_kernel_2t"] == 0.9 and m["stream_2t"] == 0.3
    assert m["busy_cores"] == 0.25                               # the worse load figure
    assert m["steal"] == pytest.approx(0.04)
    assert a[("hair", "eval", "float32")]["kernel_1t"] == 2.0     # inputs untouched


def test_merge_cells_variant_only_in_one_pass(tp):
    a = {("k", "pdf", "float64"): {"kernel_1t": 1.0, "steal": None}}
    b = {("k", "pdf", "float64"): {"kernel_1t": 3.0, "plain_2t": 0.7, "steal": 0.1}}
    m = tp.merge_cells(a, b)[("k", "pdf", "float64")]
    assert m == {"kernel_1t": 1.0, "plain_2t": 0.7, "steal": 0.1}
    # a measured zero is a value, not a missing one
    z = tp.merge_cells({"c": {"steal": 0.0}}, {"c": {"steal": None}})["c"]
    assert z["steal"] == 0.0


def test_steal_share(tp):
    assert tp.steal_share((10, 1000), (60, 2000)) == pytest.approx(0.05)
    assert tp.steal_share(None, (60, 2000)) is None
    assert tp.steal_share((10, 1000), (10, 1000)) is None       # no time passed
    t = tp.steal_ticks()
    if t is not None:                                            # Linux: steal <= total jiffies
        assert 0 <= t[0] <= t[1] and not math.isnan(t[0])


def test_cell_info_is_not_a_timing(tp):
    # build_rows must not turn a cell's load figures into bsdfkit "rates"
    assert set(tp.CELL_INFO) == {"busy_cores", "steal"}


def test_arith_times_stay_out_of_bsdfkit_rates(tp):
    key = ("diffuse", "eval", "float32")
    cell = {"kernel_1t": 2e-3, "kernel_2t": 1.2e-3, "stream_1t": 1e-3, "stream_2t": 6e-4,
            "arith_1t": 0.011, "arith_2t": 0.0165, "busy_cores": 0.0, "steal": 0.0}
    (row,) = tp.build_rows(1000, {key: cell}, ["diffuse"], ["eval"], ["float32"], 1, with_copy=False)
    assert set(row["bk_time"]) == {"kernel_1t", "kernel_2t"}
    assert row["arith"] == {"time_1t": 0.011, "time_2t": 0.0165}
    assert tp.arith_scaling(row) == pytest.approx(2 * 0.011 / 0.0165)   # 1.333x
    (bare,) = tp.build_rows(1000, {key: {"kernel_1t": 1.0}}, ["diffuse"], ["eval"], ["float32"], 1, with_copy=False)
    assert bare["arith"] is None and tp.arith_scaling(bare) is None


@pytest.mark.parametrize("sc, bk2, b2, host, verdict", [
    (1.85, 100, 1000, None, "met"),        # the target itself
    (1.5, 850, 1000, None, "bound"),       # 2 threads at 0.85 of the memory bound
    (1.5, 100, 1000, None, "NOT met"),     # no bound, no probe
    (1.25, 100, 1000, 1.35, "bound"),      # the host scaled 1.35x: 1.25 >= 0.9 * 1.35
    (1.15, 100, 1000, 1.35, "NOT met"),    # below 0.9 of the host's own scaling
    (1.7, 100, 1000, 2.05, "NOT met"),     # two free cores: the probe excuses nothing
    (1.7, 100, 0, 1.85, "bound"),          # 1.7 >= 0.9 * 1.85, no memory bound measured
])
def test_judge_scaling(tp, sc, bk2, b2, host, verdict):
    v, text = tp.judge_scaling(sc, bk2, b2, host)
    assert v == verdict
    assert f"{sc:.2f}×" in text
    if host and verdict != "met":
        assert f"{host:.2f}×" in text


def test_arith_probe_runs(tp):
    # builds tools/perf/divider.cpp as the bench does and runs its `arith` mode: two positive times
    # (no timing claim: the figures depend on the host)
    pytest.importorskip("drjit")
    assert tp.build_divider() == tp.ARITH["exe"]
    t1, t2 = tp.arith_probe()
    assert 0 < t1 < 10 and 0 < t2 < 10


def test_stream_bound_pass(tp, monkeypatch):
    # `divider stream R W` covers exactly the kernel's bytes (rounded up to whole 64-byte lines)
    # and stream_bound uses it; without the build, the numpy stand-in (named in the report)
    pytest.importorskip("drjit")
    import json
    import subprocess
    exe = tp.build_divider()
    for rb, wb in ((24_000_000, 4_000_000), (3 * 4 * 1001, 7), (64, 0)):
        for extra in ([], ["zeros"]):
            out = json.loads(subprocess.run([str(exe), "stream", str(rb), str(wb)] + extra, check=True,
                                            capture_output=True, text=True, timeout=120).stdout)
            assert out["bytes_read"] == -(-rb // 64) * 64 and out["bytes_written"] == -(-wb // 64) * 64
            assert 0 < out["stream_1t"] < 1 and 0 < out["stream_2t"] < 1
            # the pass writes data (every word non-zero, as a kernel's outputs) unless told zeros
            # (the delta lobes' eval / pdf): this host's memory writes zero lines ~3x faster
            assert out["nonzero_words"] == (0 if extra else out["bytes_written"] // 8)
    bad = subprocess.run([str(exe), "stream", "64", "64", "zero"], capture_output=True, text=True, timeout=60)
    assert bad.returncode != 0 and "zero" in bad.stderr
    calls = []
    real_run = subprocess.run

    def spy(args, *a, **k):
        calls.append(list(args))
        return real_run(args, *a, **k)

    monkeypatch.setattr(tp.subprocess, "run", spy)
    t1, t2 = tp.stream_bound(2_400_000, 400_000, 1)
    assert tp.STREAM["method"] == "c++" and 0 < t1 < 1 and 0 < t2 < 1 and calls[-1][-1] == "400000"
    tp.stream_bound(2_400_000, 400_000, 1, zeros=True)
    assert calls[-1][-1] == "zeros"
    monkeypatch.setitem(tp.ARITH, "exe", None)
    t1, t2 = tp.stream_bound(2_400_000, 400_000, 1)
    assert tp.STREAM["method"] == "numpy" and 0 < t1 < 1 and 0 < t2 < 1
    assert np.all(tp._STREAM_BUFFERS[(2_400_000, 400_000)][1] == tp.STREAM_DATA_WORD)
    tp.stream_bound(2_400_000, 400_000, 1, zeros=True)
    assert not tp._STREAM_BUFFERS[(2_400_000, 400_000)][1].any()


def test_stream_writes_named_in_method(tp):
    # the report's Method says what the run's stream pass wrote: data (rows record it, session 29
    # on) or, for an older run's JSON re-rendered with --report, zeros for every row
    data = [{"stream": {"writes": "data"}}, {"stream": {"writes": "zeros"}}, {"stream": None}]
    old = [{"stream": {"read_bytes": 1}}, {"stream": None}]
    assert tp.stream_writes_data(data) and not tp.stream_writes_data(old)


def test_report_names(tp):
    assert tp.report_names() == ("RESULTS.md", "results.json")
    assert tp.report_names("zen4") == ("RESULTS_zen4.md", "results_zen4.json")
    assert tp.host_tag("zen4") == "zen4"


@pytest.mark.parametrize("bad", ["", "../x", "a b"])
def test_bad_tag_stops_before_measuring(tp, monkeypatch, capsys, bad):
    # argparse rejects it (exit status 2) while parsing, before any cell is timed
    monkeypatch.setattr(sys, "argv", ["throughput.py", "--tag", bad])
    with pytest.raises(SystemExit) as e:
        tp.main()
    assert e.value.code == 2
    assert "--tag" in capsys.readouterr().err


@pytest.mark.parametrize("value, have, memory, contract, verdict", [
    (0.5, 500, 4000, 550, "contract-bound"),  # 0.91 of the contract bound, far from the memory bound
    (0.3, 300, 4000, 550, "NOT met"),          # 0.55 of the contract bound
    (0.3, 300, 4000, None, "NOT met"),         # no contract bound measured: the memory bound alone
    (0.5, 500, 600, 550, "bound"),             # 0.83 of the memory bound: the machine's bound comes first
    (1.3, 1300, 4000, 550, "met"),             # the target itself
    (0.9, 900, 4000, 1400, "NOT met"),         # at 0.64 of a contract bound above the target's need
    (1.1, 1100, 4000, 1150, "contract-bound"),  # 0.96 of a contract bound the target (1200) exceeds by 4 %
])
def test_judge_contract_bound(tp, value, have, memory, contract, verdict):
    # judge(value, target, need_rate, memory bound, have_rate, divider bound, contract bound)
    v, text = tp.judge(value, 1.2, 1200, memory, have, None, contract)
    assert v == verdict
    if contract and verdict in ("contract-bound", "NOT met"):
        assert f"contract bound {contract}" in text


@pytest.mark.parametrize("have, contract, expect", [
    (500.0, 1000.0, 1000.0),  # 2 ns per element less the contract's 1 ns: 1 ns, 1000 M/s
    (750.0, 1500.0, 1500.0),
    (400.0, 2000.0, 500.0),   # 2.5 ns - 0.5 ns = 2 ns
    (1000.0, 1000.0, None),   # as fast as the contract bound: no split
    (1200.0, 1000.0, None),   # faster than it (overlap): no split
    (500.0, None, None),      # no contract bound measured
])
def test_model_only_rate(tp, have, contract, expect):
    m = tp.model_only_rate(have, contract)
    assert (m is None) if expect is None else m == pytest.approx(expect, rel=1e-12)


@pytest.mark.parametrize("have, contract, limited", [
    # Mitsuba's kernel runs 1000 M/s (need_rate 1200 at target 1.2)
    (700.0, 1500.0, "contract-limited"),  # 1/700 - 1/1500 ns: model alone ~1312 M/s = 1.31x
    (500.0, 1500.0, "model-limited"),     # model alone 750 M/s = 0.75x
])
def test_judge_splits_not_met_rows(tp, have, contract, limited):
    v, text = tp.judge(have / 1000.0, 1.2, 1200.0, 10000.0, have, None, contract)
    assert v == "NOT met"
    m = 1.0 / (1.0 / have - 1.0 / contract)
    assert f"model code alone ~{m:.0f} M/s = {m / 1000.0:.2f}× ({limited})" in text


def test_report_rerenders_a_results_json(tp, tmp_path, monkeypatch):
    # --report re-renders the committed Zen 4 run without measuring: the same table, the re-render noted
    src = tp.RESULTS / "results_zen4.json"
    monkeypatch.setattr(sys, "argv", ["throughput.py", "--report", str(src), "--tag", "zen4", "--out-dir", str(tmp_path)])
    tp.main()
    text = (tmp_path / "RESULTS_zen4.md").read_text()
    assert "re-rendered from that run's measurements (`results_zen4.json`)" in text
    assert "Summary: met: " in text and "Of the NOT met verdicts: " in text
    # the committed report is this script's rendering of its JSON (a fresh run's report lacks the note)
    def body(t):  # the report without the re-render note's paragraph
        lines = t.splitlines()
        at = next((k for k, line in enumerate(lines) if line.startswith("This report was re-rendered")), None)
        if at is not None:
            del lines[at:at + 2]  # the note and the blank line after it
        return "\n".join(lines)
    assert body(text) == body((tp.RESULTS / "RESULTS_zen4.md").read_text())


def test_report_takes_the_tag_from_the_file_name(tp, tmp_path, monkeypatch):
    # results_zen4.json without --tag: RESULTS_zen4.md, not RESULTS.md (another host's report)
    src = tmp_path / "results_zen4.json"
    src.write_text((tp.RESULTS / "results_zen4.json").read_text())
    monkeypatch.setattr(sys, "argv", ["throughput.py", "--report", str(src), "--out-dir", str(tmp_path)])
    tp.main()
    assert (tmp_path / "RESULTS_zen4.md").exists() and not (tmp_path / "RESULTS.md").exists()


def test_report_refuses_a_non_results_file(tp, tmp_path, monkeypatch):
    bad = tmp_path / "x.json"
    bad.write_text("{}")
    monkeypatch.setattr(sys, "argv", ["throughput.py", "--report", str(bad), "--out-dir", str(tmp_path)])
    with pytest.raises(SystemExit) as e:
        tp.main()
    assert "--report" in str(e.value.code)


def test_contract_times_stay_out_of_bsdfkit_rates(tp):
    key = ("diffuse", "sample", "float32")
    cell = {"kernel_1t": 2e-3, "kernel_2t": 1.1e-3, "contract_1t": 1.5e-3, "contract_2t": 8e-4}
    (row,) = tp.build_rows(1000, {key: cell}, ["diffuse"], ["sample"], ["float32"], 1, with_copy=False)
    assert set(row["bk_time"]) == {"kernel_1t", "kernel_2t"}
    assert row["contract"]["rate_1t"] == pytest.approx(1000 / 1.5e-3)
    assert row["contract"]["rate_2t"] == pytest.approx(1000 / 8e-4)


def test_contract_bound_runs(tp):
    # builds loop_ab's null-model harness as the bench does and times one op: two positive times
    # (no timing claim: the figures depend on the host)
    pytest.importorskip("drjit")
    import shutil
    if shutil.which("g++") is None:
        pytest.skip("needs g++")
    exe = tp.build_contract(("float32",))
    assert "float32" in exe and tp.CONTRACT["error"] is None
    t1, t2 = tp.contract_bound("pdf", "float32", 40_000, 1)
    assert 0 < t1 < 1 and 0 < t2 < 1
