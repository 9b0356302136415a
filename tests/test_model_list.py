"""The one model list (cpp/include/bsdfkit/bxdfs/all.h) generates every capability of a model:
its compiled class, its spectral form (``_core.<Name>Spectral``, from the model's ``Spectral``
trait), ``eval_grad`` (its ``GradColumns`` trait) and the spectral renderer's material. These
tests check what ``_core`` exposes against the list and the Python registry, with no list of
model names here."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import _core
from bsdfkit.models import _spectral, registry


def _forms():
    return {n: getattr(_core, n + "Spectral") for n in _core.model_names() if hasattr(_core, n + "Spectral")}


def test_every_spectral_form_declares_fields_of_its_model():
    forms = _forms()
    assert len(forms) >= 15
    for name, form in forms.items():
        fields = set(getattr(_core, name).fields)
        for field, kind in form.spectral_fields:
            assert field in fields, (name, field)
            assert kind in ("reflectance", "unbounded"), (name, field, kind)


def test_spectral_classes_are_read_from_core():
    names = {c.__name__ for c in _spectral.spectral_classes()}
    owners = set()
    for core_name in _forms():
        owner = max((c.__name__ for c in registry.classes() if core_name.startswith(c.__name__)), key=len)
        owners.add(owner)
    assert names == owners
    assert "Custom" not in names
    assert bk.render.SPECTRAL_MODELS == tuple(c.__name__ for c in _spectral.spectral_classes())


def test_generic_form_constructor_names_bad_inputs():
    sp = _core.SpectralParam.constant(0.5)
    with pytest.raises(TypeError, match="DiffuseSpectral: missing spectral input 'reflectance'"):
        _core.DiffuseSpectral({})
    with pytest.raises(TypeError, match=r"DiffuseSpectral.reflectance: expected a _core.SpectralParam, got float"):
        _core.DiffuseSpectral({"reflectance": 0.5})
    with pytest.raises(TypeError, match="unexpected spectral input 'colour'"):
        _core.DiffuseSpectral({"reflectance": sp, "colour": sp})
    with pytest.raises(TypeError, match="unexpected keyword argument 'albedo'"):
        _core.DiffuseSpectral({"reflectance": sp}, albedo=1.0)
    with pytest.raises(ValueError, match="spec_weight: must be in"):
        _core.PlasticSpectral({"reflectance": sp, "specular_reflectance": sp, "spec_weight": 1.5,
                               "has_diffuse": True})


def test_generic_form_equals_the_rgb_model_for_constant_spectra():
    """ColourSpectral (the generic form) builds the model itself with 4 channels: a grey
    reflectance gives the RGB value at every wavelength, bit for bit, on both paths."""
    rng = np.random.default_rng(3)
    v = rng.normal(size=(2, 5000, 3))
    wo, wi = v / np.linalg.norm(v, axis=-1, keepdims=True)
    lam = rng.uniform(360, 830, size=(5000, 4))
    for m in (bk.Diffuse(0.3), bk.DiffuseTransmission(0.2, 0.7)):
        rgb = m.eval(wo, wi)
        spec = m.eval(wo, wi, wavelengths=lam)
        np.testing.assert_array_equal(spec, np.repeat(rgb[:, :1], 4, axis=1))
        np.testing.assert_array_equal(m.pdf(wo, wi, wavelengths=lam), m.pdf(wo, wi))


def test_every_differentiable_model_names_its_fields():
    grads = [n for n in _core.model_names() if hasattr(getattr(_core, n), "eval_grad")]
    assert len(grads) >= 10
    for name in grads:
        cls = getattr(_core, name)
        assert cls.grad_max_columns in (4, 8, 16)
        assert cls.grad_fields and {f for f, _ in cls.grad_fields} <= set(cls.fields), name
