"""Force signals of impact firmness sensors: recordings, their analysis, and a synthetic line with a known truth.

* ``recording``: ``Recording``, force lanes [N] sampled together at one rate [Hz];
* ``read``: ``read_recording(path)`` for CSV, NumPy ``.npy``, raw float32 and NI TDMS files, and
  ``open_recording(path)`` to read any length in chunks (memory bounded by the chunk);
* ``settings``, ``filters``, ``detect``: the causal detector of contacts (``Detector``, ``DetectorSettings``);
* ``indices``: F_max, t_c, T and the firmness indices C and C* of a contact; ``fit``: the simulator's pulse
  fitted to it (``fit_impact``); ``split``: two overlapping pulses; ``rebounds``: rebound decisions by the
  fruit's own physics; ``sort``: firmness classes;
* ``analysis``: all of that for each detected contact; ``options``: the analysis options, checked once for
  the CLI and the API; ``stream``: ``StreamAnalyzer`` (samples pushed as they come) and the TCP server;
  ``offline``: ``analyze`` (a whole recording → a table);
* ``synth``: ``SensorModel``, ``Impact``, ``Population``, ``synthesize`` (recording + truth),
  ``write_recording``, ``write_truth``.

SI units throughout.  The names below are imported on first use, so that importing one module (the CLI's
parser reads ``settings.MAX_RATE``) does not load the readers, the generator or numba.
"""

import importlib

_EXPORTS = {"open_recording": "read", "read_recording": "read", "Recording": "recording",
            **{name: "synth" for name in ("Impact", "Population", "SensorModel", "synthesize", "truth_path",
                                          "write_recording", "write_truth")}}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'fruitimpact.signals' has no attribute {name!r}")
    return getattr(importlib.import_module(f"fruitimpact.signals.{module}"), name)
