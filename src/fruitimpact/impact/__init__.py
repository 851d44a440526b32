"""One impact and tables of impacts: the quantities, their validation, the solvers and the results.

* ``quantities``: the one table of quantities (name, unit, range, meaning) that drives the CLI options,
  the input and output columns, validation and results;
* ``units``: unit strings (``65mm``, ``115g``, ``3MPa``) to SI;
* ``validation``: range and consistency checks of inputs, the one ``InputError`` message format;
* ``labels``: the row labels of a table of inputs;
* ``inputs``: reading and checking columns of inputs (tables, CSV, Parquet);
* ``status``: the status of each result (ok / warning / invalid / failed) and its message;
* ``presets``: library fruit and surface presets, lot spreads and per-fruit defaults;
* ``distributions``: parameter distributions of a lot (``normal(...)``, ``split-normal(...)``, ...);
* ``registries``: the choices the CLI offers (surfaces, models, solvers);
* ``solvers``: the solver registry (exact, adaptive, fixed-step RK4);
* ``evaluation``: the vectorised table path: rows of inputs to characteristics (:func:`evaluate`);
* ``simulation``: one impact with curves (:func:`simulate`, :class:`ImpactResult`);
* ``outputs``: output formats and atomic writes.

Nothing is imported here, so that importing one module does not compile the engine.
"""
