"""
The instrument, one stage a module, in the order the light meets them.

``filters`` (the filter model) → ``channels`` (Stokes spectra → six planes) →
``scene`` (the planes on the sky) → ``optics`` (PSF and pixels) → ``camera``
(frames, noise, raw planes) → ``reduction`` (raw planes → observables).
"""
__all__ = []
