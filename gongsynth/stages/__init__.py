"""
The stages every instrument shares, one a module, in the order the light meets them.

``channels`` (Stokes spectra → the instrument's K planes, filter first) →
``scene`` (the planes on the sky) → ``optics`` (PSF and pixels) → ``camera``
(frames, noise, raw planes) → ``reduction`` (raw planes → observables).  What
is each instrument's own (filters, schedule, algorithm) is in
`gongsynth.instruments`; a stage asks the instrument, never tests which it is.
"""
__all__ = []
