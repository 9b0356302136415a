"""Every compiled model (cpp/include/bsdfkit/bxdfs/all.h, listed by ``_core.model_names()``)
renders in the preview renderer, and its keyword constructor follows its C++ Params.

The renderer's material is the variant over the same list the bindings are generated from, so a
model that is bound but not renderable cannot be compiled; these tests check it end to end
(issue 10: the clear-coat Filament kernels were bound but missing from the renderer's list).
"""
import types

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import _core

NAMES = _core.model_names()

# Params fields that hold a shared table (core/table.h) have no default: the test supplies one
# (by field name; `table` by the model: MERL tables for MERLNearest/MERLLinear, a tensor file's for Measured).
TABLES = {"dfg": lambda name: bk.filament._table(32),
          "table": lambda name: (bk.MERL.from_metal("Cu", alpha=0.3)._keep[0] if name.startswith("MERL")
                                 else bk.Measured.from_metal("Au", alpha=0.3, resolution=8)._keep[2])}


def _default_core(name):
    cls = getattr(_core, name)
    return cls(**{f: make(name) for f, make in TABLES.items() if f in cls.fields})


def _preview(core_or_model):
    m = core_or_model if hasattr(core_or_model, "_core") else types.SimpleNamespace(_core=core_or_model)
    return bk.render.preview(m, width=8, height=8, spp=1, max_depth=3, progress=False)


def test_model_names_is_the_compiled_list():
    assert len(NAMES) == len(set(NAMES)) >= 15
    for name in ("Diffuse", "DiffuseTransmission", "Conductor", "ConductorSchlick", "ConductorF82", "Dielectric",
                 "ThinDielectric", "FilamentStandard", "FilamentStandardCoat", "FilamentStandardSheen",
                 "FilamentStandardCoatSheen", "FilamentCloth", "NormalizedFresnel", "Hair", "HairFarField"):
        assert name in NAMES
    for name in NAMES:
        cls = getattr(_core, name)
        assert isinstance(cls.fields, tuple) and cls.fields and all(isinstance(f, str) for f in cls.fields)


@pytest.mark.parametrize("name", NAMES)
def test_every_compiled_model_renders(name):
    img = _preview(_default_core(name))
    assert img.shape == (8, 8, 3) and img.dtype == np.float32
    assert np.all(np.isfinite(img))
    assert float(img.sum()) > 0


def test_clear_coat_filament_renders():
    # the reported bug: the model is a FilamentStandardCoat kernel
    m = bk.FilamentStandard(base_color=(0.05, 0.2, 0.7), metallic=0.7, clear_coat=1.0)
    assert type(m._core).__name__ == "FilamentStandardCoat"
    img = _preview(m)
    assert np.all(np.isfinite(img)) and float(img.sum()) > 0


@pytest.mark.parametrize("name", NAMES)
def test_params_round_trip(name):
    core = _default_core(name)
    p = core.params
    assert tuple(p) == type(core).fields            # one entry per field, in the visitor's order
    again = type(core)(**p)
    assert again.params == p
    wo = np.array([[0.3, 0.2, np.sqrt(1 - 0.13)]])
    wi = np.array([[-0.4, 0.1, np.sqrt(1 - 0.17)]])
    a, b = np.empty((1, 3)), np.empty((1, 3))
    core.eval(wo, wi, 0, a)
    again.eval(wo, wi, 0, b)
    assert np.array_equal(a, b)


@pytest.mark.parametrize("model", [bk.Diffuse(), bk.DiffuseTransmission(), bk.Dielectric(), bk.ThinDielectric(),
                                   bk.FilamentStandard(dfg_lut_size=32), bk.FilamentCloth(dfg_lut_size=32)],
                         ids=lambda m: type(m).__name__)
def test_params_defaults_are_the_python_defaults(model):
    # a keyword left out takes the C++ Params default, which is the Python class's default
    assert model._core.params == _default_core(type(model._core).__name__).params


def test_keyword_constructor_names_bad_input():
    with pytest.raises(TypeError, match="Dielectric: unexpected keyword argument 'etaa'"):
        _core.Dielectric(etaa=1.5)
    with pytest.raises(TypeError, match=r"Dielectric: takes keyword arguments only"):
        _core.Dielectric(1.5)
    with pytest.raises(TypeError, match=r"Dielectric\.eta: expected a real number, got str"):
        _core.Dielectric(eta="1.5")
    with pytest.raises(TypeError, match=r"Dielectric\.eta: expected a real number, got bool"):
        _core.Dielectric(eta=True)
    with pytest.raises(ValueError, match=r"Dielectric\.alpha_x: must be finite"):
        _core.Dielectric(alpha_x=float("nan"))
    with pytest.raises(ValueError, match=r"Dielectric\.masking: must be one of 'correlated', 'separable'"):
        _core.Dielectric(masking="smith")
    with pytest.raises(ValueError, match=r"Conductor\.masking: must be one of"):
        _core.Conductor(masking=2)
    with pytest.raises(ValueError, match=r"Conductor\.eta: expected 3 real numbers"):
        _core.Conductor(eta=[1.0, 2.0])
    with pytest.raises(TypeError, match=r"Conductor\.k\[1\]: expected a real number"):
        _core.Conductor(k=[1.0, None, 2.0])
    with pytest.raises(TypeError, match=r"FilamentCloth\.has_subsurface: expected a bool"):
        _core.FilamentCloth(has_subsurface=1, dfg=bk.filament._table(32))
    with pytest.raises(TypeError, match=r"FilamentStandard: missing required keyword argument 'dfg'"):
        _core.FilamentStandard()
    with pytest.raises(TypeError, match=r"FilamentStandard\.dfg: expected a _core\.FilamentDFG"):
        _core.FilamentStandard(dfg=np.zeros((4, 4, 3)))
    # enum fields accept the name or the index
    assert _core.Dielectric(masking="separable").params["masking"] == "separable"
    assert _core.Dielectric(masking=1).params["masking"] == "separable"
    assert _core.Dielectric(eta=np.float32(1.25)).params["eta"] == 1.25


def test_dfg_table_digest_identifies_values():
    a, b = bk.filament._table(32), bk.filament._table(16)
    same = _core.FilamentDFG(a.array(), a.samples)
    assert same is not a and same == a and hash(same) == hash(a) and same.digest == a.digest
    assert b != a and b.digest != a.digest
