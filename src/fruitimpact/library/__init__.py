"""The fruit and surface libraries: sourced property values with their ranges and sources.

* ``catalogue``: reads ``data/fruits.csv`` and ``data/surfaces.csv`` (standard library only), checks them
  and serves them as frozen records (:func:`fruit`, :func:`surface`, :func:`fruits`, :func:`surfaces`); reads
  and writes fruit files, one fruit in the library's own format (:func:`read_fruit_file`,
  :func:`fruit_file_text`), which every ``fruit`` input accepts in place of a library name (found by its path only;
  its values pass the checks of the options they stand for, :func:`fruitimpact.impact.validation.fruit_file_warnings`).

docs/library.md has the tables, their sources and what the flags mean.
"""

from fruitimpact.library.catalogue import (ENERGY_BASED, ENERGY_BASES, FITTED_BY, FRUIT_COLUMNS,
                                           FRUIT_UNITS, SURFACE_MODELS, SURFACE_UNITS, Fruit, FruitRegistry,
                                           LibraryError, Surface, Value, fitted_criterion,
                                           fitted_criterion_message, fruit, fruit_file_text,
                                           fruit_rows, fruits, is_fruit_file, load_fruit_file,
                                           read_fruit_file, surface, surface_rows, surfaces)

__all__ = ["ENERGY_BASED", "ENERGY_BASES", "FITTED_BY", "FRUIT_COLUMNS", "FRUIT_UNITS", "SURFACE_MODELS",
           "SURFACE_UNITS", "Fruit", "FruitRegistry", "LibraryError", "Surface", "Value", "fitted_criterion",
           "fitted_criterion_message", "fruit",
           "fruit_file_text", "fruit_rows", "fruits", "is_fruit_file", "load_fruit_file",
           "read_fruit_file", "surface", "surface_rows", "surfaces"]
