"""Bounded, seeded mutation fuzz of the scene importers (issue 50, item 18): every mutated pbrt-v4
text or Mitsuba plugin dict imports into models with finite values, or raises ValueError /
TypeError (/ OSError for files) naming where -- never another exception. Found by it and fixed:
a plugin 'type' that is not a string (numpy's ambiguous-truth ValueError), ext_ior 0 for hair
(ZeroDivisionError), an infinite hair 'scale'."""
import copy
import random
import warnings

import numpy as np
import pytest

import bsdfkit as bk

WO = bk.direction(np.radians([10.0, 50.0, 80.0]), 0.0)
WI = bk.direction(np.radians([20.0, 45.0, 70.0]), np.pi)

PBRT = '''Option "bool disablepixeljitter" true
LookAt 0 0 5  0 0 0  0 1 0
Camera "perspective" "float fov" [45]
ActiveTransform StartTime
Translate 0 0 1
ActiveTransform All
WorldBegin
AttributeBegin
  MakeNamedMaterial "gold" "string type" "conductor" "spectrum eta" "metal-Au-eta" "spectrum k" "metal-Au-k"
      "float roughness" 0.01
  NamedMaterial "gold"
  Shape "sphere" "float radius" 0.5
AttributeEnd
Material "diffuse" "rgb reflectance" [0.5 0.4 0.3]
Material "dielectric" "spectrum eta" "glass-BK7" "float roughness" 0.1
Material "diffusetransmission" "rgb reflectance" [0.3 0.6 0.1] "float scale" 2
Material "conductor" "spectrum eta" [400 0.2 500 0.3 600 0.4 700 0.5] "rgb k" [3 2 1] "float uroughness" 0.2
    "float vroughness" 0.05 "bool remaproughness" false
Material "thindielectric" "float eta" 1.33
Material "hair" "float eumelanin" 0.3
MakeNamedMaterial "wood" "string type" "coateddiffuse" "rgb reflectance" [0.6 0.3 0.1] "float roughness" 0.04
'''
PBRT_TOKENS = ['"', "[", "]", "#", "0", "-1", "1e308", "nan", "inf", '"float', '"rgb', '"spectrum', "true", "Include",
               "Shape", "Material", '"string type"', "\\", "\n", " ", "AttributeEnd", "ActiveTransform", "1e9",
               '"integer maxdepth" 1000000']


def _mutate_text(rng, s):
    s = list(s)
    for _ in range(rng.randint(1, 4)):
        op, i = rng.random(), rng.randrange(len(s) + 1)
        if op < 0.3 and s:
            del s[min(i, len(s) - 1)]
        elif op < 0.6:
            s.insert(i, rng.choice(PBRT_TOKENS))
        elif op < 0.8 and s:
            s[min(i, len(s) - 1)] = chr(rng.randrange(32, 127))
        else:
            s[i:i] = s[i:min(len(s), i + rng.randint(1, 40))]
    return "".join(s)


def _finite(models):
    for m in models:
        if type(m).__name__ in ("CoatedDiffuse", "CoatedConductor"):
            continue                       # random walks: their eval is checked by the contract suite
        f = m.eval(WO, WI)
        assert np.all(np.isfinite(f)) and np.all(f >= 0), m


@pytest.mark.parametrize("seed", range(4))
def test_mutated_pbrt_text(seed):
    rng = random.Random(seed)
    for k in range(150):
        text = _mutate_text(rng, PBRT)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ms = bk.from_pbrt(text, skip_unsupported=bool(k % 2))
        except (ValueError, OSError) as e:
            assert "line" in str(e) or "pbrt material" in str(e), (str(e), text)
            continue
        _finite(ms.values())


MI = [
    {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.1, 0.2, 0.3]}},
    {"type": "roughconductor", "material": "Cu", "alpha": 0.3, "distribution": "ggx"},
    {"type": "roughconductor", "alpha_u": 0.3, "alpha_v": 0.05, "distribution": "ggx", "eta": 1.5, "k": 2.0},
    {"type": "conductor", "eta": {"type": "spectrum", "value": [(400, 0.2), (500, 0.4), (700, 1.0)]}, "k": [3, 2, 1]},
    {"type": "roughdielectric", "int_ior": "bk7", "alpha": 0.2, "distribution": "ggx"},
    {"type": "thindielectric", "int_ior": 1.5},
    {"type": "roughplastic", "diffuse_reflectance": 0.4, "alpha": 0.1, "distribution": "ggx"},
    {"type": "twosided", "bsdf": {"type": "roughconductor", "alpha": 0.2, "distribution": "ggx", "material": "Al"}},
    {"type": "hair", "eumelanin": 0.5, "pheomelanin": 0.1, "longitudinal_roughness": 0.2},
    {"type": "hair", "sigma_a": [0.3, 0.4, 0.9], "scale": 2.0},
]
VALUES = [0, -1, 1e308, float("nan"), float("inf"), "x", "", None, True, [], [1, 2], [1, 2, 3, 4], {"type": "rgb"},
          {"type": "spectrum", "value": []}, {"type": "spectrum", "value": [(300, 1)]}, {"type": "bitmap"},
          np.array([0.5, 0.5, 0.5]), "beckmann", 1 + 2j, object(), [float("nan")] * 3]
KEYS = ["type", "alpha", "alpha_u", "alpha_v", "eta", "k", "int_ior", "ext_ior", "reflectance", "diffuse_reflectance",
        "specular_reflectance", "material", "distribution", "nonlinear", "bsdf", "sigma_a", "scale", "eumelanin",
        "longitudinal_roughness", "scale_tilt", "zzz"]


def _mutate_dict(rng, d):
    d = copy.deepcopy(d)
    tgt = d["bsdf"] if "bsdf" in d and rng.random() < 0.5 else d
    for _ in range(rng.randint(1, 3)):
        r = rng.random()
        if r < 0.5:
            tgt[rng.choice(KEYS)] = rng.choice(VALUES)
        elif r < 0.7 and tgt:
            tgt.pop(rng.choice(list(tgt)))
        elif tgt:
            k = rng.choice(list(tgt))
            v = tgt[k]
            tgt[k] = v * rng.choice([-1, 0, 1e10, 1e-10]) if isinstance(v, float) else rng.choice(VALUES)
    return d


@pytest.mark.parametrize("seed", range(4))
def test_mutated_mitsuba_dicts(seed):
    rng = random.Random(seed)
    for _ in range(400):
        d = _mutate_dict(rng, rng.choice(MI))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)    # no silent overflow / nan on the way
                m = bk.from_mitsuba(d)
        except (ValueError, TypeError) as e:
            assert "from_mitsuba" in str(e), (str(e), d)
            continue
        _finite([m])
