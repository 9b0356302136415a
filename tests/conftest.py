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


def grazing_dirs(rng, n, zs, sign=1.0):
    """Directions with |z| taken from zs (cycled) and random azimuth."""
    z = np.resize(np.asarray(zs, dtype=np.float64), n) * sign
    phi = rng.uniform(0, 2 * np.pi, n)
    r = np.sqrt(np.maximum(0, 1 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


# One representative of every model family and its main variants; used by generic tests.
MODEL_CASES = {
    "diffuse": lambda: bk.Diffuse([0.8, 0.5, 0.2]),
    "difftrans": lambda: bk.DiffuseTransmission([0.3, 0.5, 0.1], [0.6, 0.2, 0.4]),
    "conductor_smooth": lambda: bk.Conductor.from_metal("Au"),
    "conductor_rough": lambda: bk.Conductor.from_metal("Cu", alpha=0.3),
    "conductor_aniso": lambda: bk.Conductor([0.2, 0.9, 1.1], [3.9, 2.4, 2.1], alpha_x=0.4, alpha_y=0.08),
    "conductor_sep": lambda: bk.Conductor.from_metal("Al", alpha=0.5, masking="separable"),
    "conductor_schlick": lambda: bk.Conductor.from_metal("Cu", fresnel="schlick"),
    "conductor_schlick_rough": lambda: bk.Conductor.from_metal("Cr", alpha=0.3, fresnel="schlick"),
    "conductor_f82": lambda: bk.Conductor.from_metal("Au", fresnel="f82"),
    "conductor_f82_rough": lambda: bk.Conductor.from_metal("Al", alpha=0.5, masking="separable", fresnel="f82"),
    "conductor_f82_aniso": lambda: bk.Conductor([0.2, 0.9, 1.1], [3.9, 2.4, 2.1], alpha_x=0.4, alpha_y=0.08,
                                                fresnel="f82"),
    "dielectric_smooth": lambda: bk.Dielectric(1.5),
    "dielectric_rough": lambda: bk.Dielectric(1.5, alpha=0.3),
    "dielectric_aniso_inv": lambda: bk.Dielectric(1 / 1.33, alpha_x=0.5, alpha_y=0.1),
    "thin": lambda: bk.ThinDielectric(1.5),
}


@pytest.fixture(params=sorted(MODEL_CASES))
def any_model(request):
    return MODEL_CASES[request.param]()


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(autouse=True, scope="session")
def _bsdfkit_disk_cache(tmp_path_factory):
    """The suite's on-disk cache (Filament DFG tables): a fresh directory per session, shared by
    its subprocesses (notebooks, CLI), unless BSDFKIT_CACHE_DIR already names one (CI may keep it)."""
    import os
    os.environ.setdefault("BSDFKIT_CACHE_DIR", str(tmp_path_factory.mktemp("bsdfkit-cache")))
