"""Argument rules a user hits (issue 11 items 7 and 11): float16 directions, partial roughness
arguments, eval(repr(m)) == m for every model, a negative seed."""
import numpy as np
import pytest

import bsdfkit as bk


def test_float16_directions_are_refused_clearly():
    m = bk.Diffuse(0.5)
    wo = np.array([0.0, 0.0, 1.0], np.float16)
    for call in (lambda: m.eval(wo, wo), lambda: m.pdf(wo, wo.astype(np.float32)), lambda: m.sample(wo, n=4),
                 lambda: m.albedo(wo)):
        with pytest.raises(TypeError, match="float16 is not supported"):
            call()


@pytest.mark.parametrize("cls, args", [(bk.Conductor, (0.2, 3.9)), (bk.Dielectric, (1.5,))])
def test_partial_roughness_is_an_error(cls, args):
    with pytest.raises(ValueError, match="alpha_y: give alpha_x and alpha_y together"):
        cls(*args, alpha_x=0.2)  # alpha_y silently 0 before
    with pytest.raises(ValueError, match="alpha_x: give alpha_x and alpha_y together"):
        cls(*args, alpha_y=0.2)
    with pytest.raises(ValueError, match="alpha: give either alpha"):
        cls(*args, alpha=0.3, alpha_x=0.2, alpha_y=0.2)  # mixed silently before
    m = cls(*args, alpha_x=0.2, alpha_y=0.1)
    assert (m.alpha_x, m.alpha_y) == (0.2, 0.1)
    assert cls(*args, alpha=0.3) == cls(*args, alpha_x=0.3, alpha_y=0.3)
    assert cls(*args).alpha_x == 0.0


def test_from_metal_anisotropic_still_works():
    m = bk.Conductor.from_metal("Al", alpha_x=0.4, alpha_y=0.1)
    assert (m.alpha_x, m.alpha_y) == (0.4, 0.1)
    with pytest.raises(ValueError, match="alpha"):
        bk.Conductor.from_metal("Al", roughness=0.1, alpha_x=0.4, alpha_y=0.1)


def _examples():
    ms = [bk.Conductor.from_metal("Cu", alpha=0.3), bk.Conductor(0.123456789, 3.987654321, alpha_x=0.1234567891,
                                                                   alpha_y=1 / 3, fresnel="f82"),
          bk.Dielectric(1 / 1.5, alpha=0.1 + 0.2), bk.ThinDielectric(1.3333333333333333), bk.Diffuse([0.1, 0.2, 1 / 3]),
          bk.DiffuseTransmission(1 / 7, 2 / 7)]
    ms += list(bk.filament.examples().values())
    return ms


@pytest.mark.parametrize("m", _examples(), ids=lambda m: type(m).__name__)
def test_eval_repr_round_trips(m):
    ns = {name: getattr(bk, name) for name in bk.__all__}
    ns.update(array=np.array, nan=float("nan"), inf=float("inf"))
    assert eval(repr(m), ns) == m  # Conductor's repr rounded to 6 digits before


def test_negative_seed_names_seed():
    m = bk.Diffuse(0.5)
    wo = bk.direction(theta=0.3, phi=0.0)
    with pytest.raises(ValueError, match="seed"):
        m.sample(wo, n=4, seed=-1)
    with pytest.raises(ValueError, match="seed"):
        m.albedo(wo, seed=-1)
