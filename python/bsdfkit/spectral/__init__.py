"""Spectral values and helpers (issue 15's foundation; pure Python + data).

* :mod:`.colorimetry`: CIE 1931 CMFs and D65 (from colour-science), the spectrum -> linear sRGB
  projection that reproduces Mitsuba 3's RGB variants.
* :mod:`.spectrum`: :class:`Spectrum`, an immutable spectral parameter value (sampled, constant,
  blackbody, named, uplifted RGB).
* :mod:`.named`: pbrt-v4's and Mitsuba 3's measured metal and glass spectra (``data/spectra.json``).
* :mod:`.uplift`: RGB -> spectrum (Jakob & Hanika 2019), the sRGB coefficient table (fitted at
  first use, cached).
* :mod:`.sampling`: :func:`sample_wavelengths` (pbrt-v4's ``SampledWavelengths``) and
  :func:`spectrum_to_rgb` (Monte Carlo colour estimates), :func:`terminate_secondary` (pbrt-v4's
  TerminateSecondary on wavelength pdfs, after a refraction through a dispersive dielectric).
"""
from .sampling import N_SPECTRUM_SAMPLES, sample_wavelengths, spectrum_to_rgb, terminate_secondary, visible_pdf
from .spectrum import Spectrum

__all__ = ["Spectrum", "sample_wavelengths", "spectrum_to_rgb", "terminate_secondary", "visible_pdf",
           "N_SPECTRUM_SAMPLES"]
