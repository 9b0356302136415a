"""Fuzzing both measured-file loaders with byte mutations of valid files (hypothesis): every
outcome is a loaded model whose values are finite, or a ValueError naming the field; never
another exception, never a crash, never a huge allocation."""
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import bsdfkit as bk
from bsdfkit.models import measured as mm


@pytest.fixture(scope="module")
def tensor_bytes():
    tab = bk.measured.tabulate(bk.Conductor.from_metal("Cu", alpha_x=0.3, alpha_y=0.2), resolution=4, n_theta=2,
                               n_phi=3)
    return tab._entry()[3]


@pytest.fixture(scope="module")
def merl_bytes(tmp_path_factory):
    p = bk.measured.write_merl(tmp_path_factory.mktemp("fz") / "d.binary", bk.Diffuse(0.4))
    return open(p, "rb").read()


MUTATION = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 255)), min_size=1, max_size=4)
def SETTINGS(n):
    return settings(deadline=None, max_examples=n, database=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
WO = np.array([[0.3, 0.2, 0.93], [0.0, 0.0, 1.0], [0.8, -0.5, 0.33]])
WO /= np.linalg.norm(WO, axis=1, keepdims=True)


def mutate(data, muts, cut):
    b = bytearray(data)
    for pos, val in muts:
        b[pos % len(b)] = val
    return bytes(b[:cut % (len(b) + 1)] if cut is not None else b)


@SETTINGS(1000)
@given(muts=MUTATION, cut=st.one_of(st.none(), st.integers(0, 10**6)))
def test_fuzz_tensor_loader(tensor_bytes, muts, cut):
    data = mutate(tensor_bytes, muts, cut)
    try:
        m = bk.Measured.from_bytes(data)
    except ValueError as e:
        assert "<tensor data>" in str(e)
        return
    f, p = m.eval(WO, WO[::-1]), m.pdf(WO, WO[::-1])
    s = m.sample(WO[0], n=16, seed=0)
    assert np.all(np.isfinite(f)) and np.all(np.isfinite(p)) and np.all(np.isfinite(s.f))


@SETTINGS(60)
@given(muts=st.lists(st.tuples(st.integers(0, 63), st.integers(0, 255)), min_size=1, max_size=4),
       cut=st.one_of(st.none(), st.integers(0, 64), st.integers(34992012 - 16, 34992012 + 16)))
def test_fuzz_merl_parser(merl_bytes, muts, cut):
    data = mutate(merl_bytes, muts, cut)
    try:
        values, measured, _, _ = mm.parse_merl(data, "fuzz.binary")
    except ValueError as e:
        assert "fuzz.binary" in str(e) and ("dims" in str(e) or "values" in str(e))
        return
    assert np.all(np.isfinite(values)) and np.all(values >= 0)


def test_fuzz_merl_values_reach_a_model(merl_bytes, tmp_path):
    """Mutated payload bytes: values that leave float32's range (a mutated exponent byte easily
    gives 1e240) fail naming the values; mutated mantissa bytes (bytes 0-5 of a float64) keep
    them in range, and the model evaluates finitely in float64 and float32."""
    rng = np.random.default_rng(0)
    n_values = (len(merl_bytes) - 12) // 8
    for mantissa_only in (False, True):
        b = bytearray(merl_bytes)
        if mantissa_only:
            pos = 12 + 8 * rng.integers(0, n_values, 200) + rng.integers(0, 6, 200)
        else:
            pos = rng.integers(12, len(b), 200)
        for q in pos:
            b[q] = rng.integers(0, 256)
        p = tmp_path / f"m{int(mantissa_only)}.binary"
        p.write_bytes(bytes(b))
        try:
            m = bk.MERL.load(p)
        except ValueError as e:
            assert not mantissa_only
            assert "values: non-finite" in str(e) or "exceeds float32's max" in str(e)
            continue
        assert mantissa_only or np.all(np.frombuffer(bytes(b), "<f8", offset=12) <= np.finfo(np.float32).max)
        assert np.all(np.isfinite(m.eval(WO, WO[::-1])))
        assert np.all(np.isfinite(m.eval(WO.astype(np.float32), WO[::-1].astype(np.float32))))
