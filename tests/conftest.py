import numpy as np
import pytest

import bsdfkit as bk


def random_dirs(rng, n, hemisphere=None, dtype=np.float64):
    """Uniform unit directions; hemisphere=+1/-1 restricts to z > 0 / z < 0."""
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    if hemisphere is not None:
        v[:, 2] = hemisphere * np.abs(v[:, 2])
    return v.astype(dtype)


def fibonacci_sphere(n):
    """n unit vectors spread evenly over the sphere (a spherical Fibonacci lattice), float64 (n, 3)."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = k * np.pi * (3 - np.sqrt(5))
    r = np.sqrt(1 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], -1)


def grazing_dirs(rng, n, zs, sign=1.0):
    """Directions with |z| taken from zs (cycled) and random azimuth."""
    z = np.resize(np.asarray(zs, dtype=np.float64), n) * sign
    phi = rng.uniform(0, 2 * np.pi, n)
    r = np.sqrt(np.maximum(0, 1 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _registry_cases():
    from bsdfkit.models import registry
    from bsdfkit.models.spec import parse_spec
    return {f"{cls.__name__}-{label}": (lambda s=spec: parse_spec(s)) for cls, label, spec in registry.examples()}


# Every registered example (bsdfkit.models.registry); used by generic tests.
MODEL_CASES = _registry_cases()


@pytest.fixture(params=sorted(MODEL_CASES))
def any_model(request):
    return MODEL_CASES[request.param]()


def random_wavelengths(rng, n):
    """(n, 4) wavelengths from pbrt-v4's visible-wavelength sampling (bk.sample_wavelengths)."""
    return bk.sample_wavelengths(rng.random(n))[0]


@pytest.fixture(autouse=True)
def _restore_threads():
    """Every test leaves bk's thread count as it found it (thread-count tests set it)."""
    n = bk.get_num_threads()
    yield
    bk.set_num_threads(n)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True, scope="session")
def _bsdfkit_disk_cache(tmp_path_factory):
    """The suite's on-disk cache (the RGB -> spectrum uplift table, Filament DFG tables): a fresh
    directory per run, shared by the xdist workers of that run and their subprocesses (notebooks,
    CLI), unless BSDFKIT_CACHE_DIR already names one (CI may keep it). Entries are keyed by content
    (spectral/uplift.py, models/filament/dfg.py) and written atomically; the uplift fit holds a file
    lock, so of two workers wanting the table one fits it (~1 min of CPU) and the other reads it."""
    import os
    base = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        base = base.parent   # xdist gives each worker <run basetemp>/<worker id>: share the run's
    d = base / "bsdfkit-cache"
    d.mkdir(exist_ok=True)
    os.environ.setdefault("BSDFKIT_CACHE_DIR", str(d))


def pytest_configure(config):
    # -m "not docs" leaves out the documentation build (tests/test_docs.py), ~20-50 s
    config.addinivalue_line("markers", "docs: builds the Sphinx documentation (sphinx-build -W)")
    # -m "not slow" leaves out slow tests whose check is also made, more cheaply, by another test;
    # scripts/test (the README's command, and CI) runs them: no check is dropped by default
    config.addinivalue_line("markers", "slow: slow, and its check is also made more cheaply elsewhere "
                                       "(deselect with -m 'not slow'; the default suite runs it)")
