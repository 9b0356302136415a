"""Docstrings a user reads with help() (issue 50, item 11): every registered model class has
one, the layered models' included (their docstring was an expression, so __doc__ was None), and
their constructors say where the parameters are instead of object's "Initialize self"; a fit's
report does not call a converged but poor fit "ok"."""
import inspect

import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit.models import registry

OWN = ("Diffuse", "DiffuseTransmission", "Conductor", "Dielectric", "ThinDielectric", "MERL", "Measured",
       "Plastic", "CoatedDiffuse", "CoatedConductor", "NormalizedFresnel", "Hair")


@pytest.mark.parametrize("cls", registry.classes(), ids=lambda c: c.__name__)
def test_every_registered_model_has_a_class_docstring(cls):
    doc = inspect.getdoc(cls)
    assert doc and len(doc) > 200 and cls.__doc__ is not None


@pytest.mark.parametrize("name", OWN)
def test_constructors_point_at_their_parameters(name):
    cls = getattr(bk, name)
    doc = inspect.getdoc(cls.__init__)
    assert "Initialize self" not in doc and name in doc and "ValueError" in doc


def test_coated_docstrings_describe_the_walk():
    for cls in (bk.CoatedDiffuse, bk.CoatedConductor):
        assert "pdf_is_proportional" in cls.__doc__ and "thickness" in cls.__doc__


def test_fit_report_does_not_call_a_poor_fit_ok():
    target = bk.Conductor.from_metal("Cu", alpha=0.1)
    m, rep = bk.fit(target, bk.Diffuse, n=512)
    assert float(np.max(rep.rel_p99)) > 0.5                    # a Lambertian cannot be a glossy metal
    text = str(rep)
    assert "ok:" not in text and "convergence only" in text
