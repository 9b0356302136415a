"""The batch kernels' thread pool and Ctrl-C (issue 11 items 5 and 9).

Pool: results are bit-identical for any thread count, from concurrent Python threads (one batch
holds the pool, the others run on their own thread) and in a forked child (whose pool has no
helper threads). Its point -- the caller never waits for a helper that has not started, so a
descheduled thread cannot stall a call for a scheduler slice -- is a timing property measured by
tools/perf/stalls.py, not asserted here.
Interrupts: a long albedo or tradeoff call stops on SIGINT with KeyboardInterrupt (run in a
subprocess that the test interrupts), as render does.
"""
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
import warnings

import numpy as np
import pytest

import bsdfkit as bk
import importlib

to = importlib.import_module("bsdfkit.tuning.costs")


@pytest.fixture
def restore_threads():
    n = bk.get_num_threads()
    yield
    bk.set_num_threads(n)


def _work(rng, n=100_003):
    wo = rng.normal(size=(n, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = rng.normal(size=(n, 3))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    return wo, wi


def test_bit_identical_for_any_thread_count(restore_threads, rng):
    m = bk.Dielectric(1.5, alpha=0.3)
    wo, wi = _work(rng)
    uc, u = rng.random(len(wo)), rng.random((len(wo), 2))
    res = []
    for nt in (1, 2, 3, 8):
        bk.set_num_threads(nt)
        s = m.sample(wo, uc, u)
        res.append((m.eval(wo, wi), m.pdf(wo, wi), s.wi, m.albedo(wo[:5], n_samples=50_000, seed=3)))
    for r in res[1:]:
        for a, b in zip(res[0], r):
            np.testing.assert_array_equal(a, b)


def test_concurrent_python_threads(restore_threads, rng):
    bk.set_num_threads(2)
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    wo, wi = _work(rng)
    want = m.eval(wo, wi)
    got, errors = [None] * 4, []

    def run(k):
        try:
            for _ in range(5):
                got[k] = m.eval(wo, wi)
        except Exception as e:  # pragma: no cover - reported below
            errors.append(e)
    ts = [threading.Thread(target=run, args=(k,)) for k in range(4)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert not errors
    for g in got:
        np.testing.assert_array_equal(g, want)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="os.fork is POSIX-only")
def test_forked_child_computes(restore_threads, rng):
    bk.set_num_threads(2)
    m = bk.Diffuse(0.5)
    wo, wi = _work(rng, 50_000)
    want = m.eval(wo, wi)  # the parent's pool now has a helper thread
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:  # child: the pool's helper does not exist here; the call must still complete
        try:
            ok = np.array_equal(m.eval(wo, wi), want)
            os.write(w, b"1" if ok else b"0")
        finally:
            os._exit(0)
    os.close(w)
    os.waitpid(pid, 0)
    assert os.read(r, 1) == b"1"


def _interrupt(code, after="started", deadline=20.0):
    """Runs `code` in a subprocess, sends SIGINT once it prints `after` (+0.5 s), returns
    (stdout, seconds from SIGINT to exit)."""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    # The child starts with SIGINT's default disposition: one inherited as ignored (a pytest-xdist
    # worker can be left ignoring it) keeps Python from installing its handler, so the child would
    # ignore the Ctrl-C under test and run to the deadline (seen in CI: 4 tests on one worker).
    p = subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, env=env,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        line = p.stdout.readline()
        assert after in line, line + p.stdout.read()
        time.sleep(0.5)
        t0 = time.perf_counter()
        p.send_signal(signal.SIGINT)
        out, _ = p.communicate(timeout=deadline)
        return line + out, time.perf_counter() - t0
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()


@pytest.mark.parametrize("threads", [1, 2])
def test_albedo_stops_on_sigint(threads):
    # ~2^31 samples: minutes of work; before the pool's interrupt hook it ran to the end
    out, dt = _interrupt(f"""
        import numpy as np, bsdfkit as bk
        bk.set_num_threads({threads})
        m = bk.Dielectric(1.5, alpha=0.3)
        print("started", flush=True)
        try:
            m.albedo(bk.direction(theta=0.5, phi=0.0), n_samples=2**31)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted")
    """)
    assert "interrupted" in out, out


def test_tradeoff_stops_on_sigint():
    out, dt = _interrupt("""
        import bsdfkit as bk
        m = bk.FilamentStandard([0.8, 0.5, 0.3], clear_coat=0.5, sheen_color=0.5)
        print("started", flush=True)
        try:
            bk.tradeoff(m, n_albedo=2**22, n_timing=2**18, repeats=50)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted")
    """)
    assert "interrupted" in out, out


# ------------------------------------------------------------------ tradeoff's timing

def test_tradeoff_reports_spread_and_warns_when_noisy(monkeypatch):
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    monkeypatch.setattr(to, "time_repeats", lambda fn, repeats=5, *a, **k: [1e-3] * repeats)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        t = bk.tradeoff(m, n=256, n_albedo=64, n_timing=256, repeats=5)  # quiet: no warning
    assert "spread" in t.columns and all(s == pytest.approx(1.0) for s in t["spread"])
    monkeypatch.setattr(to, "time_repeats", lambda fn, repeats=5, *a, **k: [1e-3, 4e-3, 5e-3, 6e-3, 7e-3][:repeats])
    with pytest.warns(RuntimeWarning, match="noisy"):
        t = bk.tradeoff(m, n=256, n_albedo=64, n_timing=256, repeats=5)
    assert all(s == pytest.approx(5.0) for s in t["spread"])
    assert "5.00!" in str(t)


def test_spread():
    assert to.spread([2.0, 1.0, 3.0]) == 2.0
    assert to.spread([1.0] * 5) == 1.0


def test_cost_deviations_flag_entries_off_by_more_than_half():
    shipped = {"families": {"Dielectric/rough": {"costs": {"precision=float64": 1.0, "precision=float32": 0.14,
                                                           "x": 0.5}}}}
    measured = {"Dielectric/rough": {"precision=float64": 1.0, "precision=float32": 0.37, "x": 0.6}}
    bad = to.cost_deviations(shipped, measured)
    assert bad == [("Dielectric/rough", "precision=float32", 0.14, 0.37)]
    assert to.cost_deviations(shipped, {"Dielectric/rough": {"x": 0.3}})  # 1.67x cheaper: flagged
    assert not to.cost_deviations(shipped, {"Dielectric/rough": {"x": 0.36}})  # 1.39x: within 50 %


def test_tabulate_stops_on_sigint():
    # resolution 256: one (N^2, 96^2) clamped-cosine matrix was 4.8 GB and ran in one numpy call
    # (10-20 s without a chance to stop at resolution 128); now formed in row blocks
    out, dt = _interrupt("""
        import bsdfkit as bk
        m = bk.Conductor.from_metal("Cu", alpha=0.3)
        print("started", flush=True)
        try:
            bk.measured.tabulate(m, resolution=256, isotropic=True)
            print("finished")
        except KeyboardInterrupt:
            print("interrupted")
    """)
    assert "interrupted" in out, out


# ------------------------------------------------------------------ Ctrl-C in long single calls (issue 50 item 18)

def _interrupt_trials(setup, loop, trials=4, deadline=20.0):
    """Runs `setup` in a subprocess, then `trials` times: the child prints "started", runs `loop`
    (which only ends by an exception), the parent sends SIGINT 0.2-0.8 s later; the child prints
    the name of the exception that ended `loop` and survives to run the next trial. Returns the
    names, one per trial, and the child's exit status."""
    body = textwrap.indent(textwrap.dedent(loop).strip("\n"), " " * 12)
    code = textwrap.dedent(setup) + f"""
for _trial in range({trials}):
    print("started", flush=True)
    try:
        while True:
{body}
    except BaseException as e:
        print("ended", type(e).__name__, flush=True)
print("survived", flush=True)
"""
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         env=env, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    rng = np.random.default_rng(50)
    names, lines = [], []
    t_end = time.monotonic() + deadline * trials

    def readline():  # the child's next line; the deadline bounds the whole run (a hang fails, not blocks)
        timer = threading.Timer(max(0.0, t_end - time.monotonic()), p.kill)
        timer.start()
        try:
            line = p.stdout.readline()
        finally:
            timer.cancel()
        lines.append(line)
        return line
    try:
        for _ in range(trials):
            while "started" not in (line := readline()):
                assert line, "".join(lines)
            time.sleep(rng.uniform(0.2, 0.8))
            p.send_signal(signal.SIGINT)
            while not (line := readline()).startswith("ended"):
                assert line, "".join(lines)
            names.append(line.split()[1])
        while "survived" not in (line := readline()):
            assert line, "".join(lines)
        return names, p.wait(timeout=deadline), "".join(lines)
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()


@pytest.mark.parametrize("threads", [1, 2])
def test_sample_n_stops_on_sigint(threads):
    # m.sample(wo, n=...) on one thread ignored SIGINT for over a minute: the seeded uniforms and
    # the kernel now stop within a chunk. A float32 random-walk model keeps the memory small
    # (~47 bytes a sample: 235 MB) while each call runs for seconds (~0.3 M samples/s a thread).
    names, rc, out = _interrupt_trials(f"""
        import bsdfkit as bk
        bk.set_num_threads({threads})
        m = bk.CoatedDiffuse(0.8, alpha=0.3, thickness=0.1, albedo=0.9)
        wo = bk.direction(0.5, 0.0).astype("float32")
        s = m.sample(wo, n=1000, seed=1)  # a warm start: the first call's set-up is not under test
    """, """
        s = None
        s = m.sample(wo, n=5_000_000, seed=1)
        print("finished", flush=True)
    """, trials=2)
    assert names == ["KeyboardInterrupt"] * 2 and rc == 0, out
    assert "finished" not in out, out


def test_merl_load_stops_on_sigint(tmp_path):
    # Ctrl-C while a MERL file loaded surfaced as "SystemError: ... returned a result with an
    # exception set" when it landed in the sampler's table build (C++): a KeyboardInterrupt now,
    # wherever it lands, and the process goes on. The loop patches one value per load, so every
    # load is a new table (no cache hit).
    nh, nd, npd = bk.measured.MERL_DIMS
    raw = np.random.default_rng(3).uniform(0.0, 1.0, (3, nh, nd, npd))
    path = tmp_path / "noise.binary"
    with open(path, "wb") as fh:  # MERL's format: 3 int32 dims, then float64 channel planes
        fh.write(np.asarray((nh, nd, npd), "<i4").tobytes())
        fh.write(raw.astype("<f8").tobytes())
    names, rc, out = _interrupt_trials(f"""
        import numpy as np, bsdfkit as bk
        bk.set_num_threads(1)
        path, k = {str(path)!r}, 0
        bk.MERL(path)
    """, """
        k += 1
        with open(path, "r+b") as fh:
            fh.seek(12 + 8 * (k % 1000))
            fh.write(np.float64(k * 1e-3).tobytes())
        m = bk.MERL(path, "linear" if k % 2 else "nearest")
    """, trials=6)
    assert names == ["KeyboardInterrupt"] * 6 and rc == 0, out
