"""The fruit and surface libraries: sourced property values with their ranges and sources.

* ``catalogue``: reads ``data/fruits.csv`` and ``data/surfaces.csv`` (standard library only), checks them
  and serves them as frozen records (:func:`fruit`, :func:`surface`, :func:`fruits`, :func:`surfaces`).

docs/library.md has the tables, their sources and what the flags mean.
"""

from fruitimpact.library.catalogue import (ENERGY_BASED, ENERGY_BASES, FRUIT_UNITS, SURFACE_MODELS, SURFACE_UNITS,
                                           Fruit, LibraryError, Surface, Value, fruit, fruit_rows, fruits, surface,
                                           surface_rows, surfaces)

__all__ = ["ENERGY_BASED", "ENERGY_BASES", "FRUIT_UNITS", "SURFACE_MODELS", "SURFACE_UNITS", "Fruit", "LibraryError",
           "Surface", "Value", "fruit", "fruit_rows", "fruits", "surface", "surface_rows", "surfaces"]
