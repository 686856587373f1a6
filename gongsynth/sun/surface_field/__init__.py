"""
The large-scale field of the whole Sun: B_r on a Carrington grid, from a real map or a synthetic Sun.

- `gongsynth.sun.surface_field.maps`: the product (a CEA Carrington
  `sunpy.map.GenericMap` of B_r in gauss), sampling it on the disk at any
  date (`surface_field_at`) and filling unobserved cells.
- `gongsynth.sun.surface_field.observed`: `surface_field_from_map`, a real
  magnetogram (full-disk or synoptic) remapped to that grid.
- `gongsynth.sun.surface_field.cycle`: the solar cycle (sunspot-number shape,
  Spörer's, Hale's and Joy's laws, polar fields).
- `gongsynth.sun.surface_field.synthetic`: `synthetic_surface_field`, a seeded
  Sun at the cycle phase of its date.
- `gongsynth.sun.surface_field.network`: the magnetic network on supergranular
  cells, laid over the large-scale field on a full-disk scene's grid, and
  `gongsynth.sun.surface_field.supergranulation`: the same cells' flow.
"""
from gongsynth.sun.surface_field.maps import fill_unobserved, surface_field_at
from gongsynth.sun.surface_field.observed import surface_field_from_map
from gongsynth.sun.surface_field.synthetic import synthetic_surface_field

__all__ = ["surface_field_from_map", "synthetic_surface_field", "surface_field_at", "fill_unobserved"]
