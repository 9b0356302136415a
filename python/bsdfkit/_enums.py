"""Enumerations mirroring pbrt-v4's names."""
import enum


class TransportMode(enum.IntEnum):
    """What a path carries: radiance (camera paths) or importance (light paths).

    Only refraction between media of different index differs: in ``Radiance`` mode the
    transmitted value is divided by eta'^2, in ``Importance`` mode it is not.
    """

    Radiance = 0
    Importance = 1


class BxDFFlags(enum.IntFlag):
    """Lobe kinds a model has, or the kind of a sampled lobe (pbrt-v4 ``BxDFFlags``)."""

    Unset = 0
    Reflection = 1
    Transmission = 2
    Diffuse = 4
    Glossy = 8
    Specular = 16
    DiffuseReflection = 5
    DiffuseTransmission = 6
    GlossyReflection = 9
    GlossyTransmission = 10
    SpecularReflection = 17
    SpecularTransmission = 18
    All = 31


class ReflTrans(enum.IntFlag):
    """Restricts sampling and pdf to reflection, transmission or both (pbrt-v4 ``BxDFReflTransFlags``)."""

    Unset = 0
    Reflection = 1
    Transmission = 2
    All = 3
