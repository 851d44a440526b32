"""Force signals of impact firmness sensors: recordings, reading them from files, and a
synthetic sensor with a known truth.

* ``recording``: ``Recording``, force lanes [N] sampled together at one rate [Hz].
* ``read``: ``read_recording(path)`` for CSV, NumPy ``.npy``, raw float32 and NI TDMS files, and
  ``open_recording(path)`` to read any length in chunks (memory bounded by the chunk).
* ``synth``: ``SensorModel``, ``Impact``, ``Population``, ``synthesize`` (recording + truth),
  ``write_recording``, ``write_truth``.

SI units throughout.  Importing this package loads neither the engine nor SciPy, pyarrow
or nptdms: each is imported by the function that needs it.
"""

from fruitimpact.signals.read import open_recording, read_recording
from fruitimpact.signals.recording import Recording
from fruitimpact.signals.synth import (
    Impact,
    Population,
    SensorModel,
    synthesize,
    truth_path,
    write_recording,
    write_truth,
)

__all__ = ["Impact", "Population", "Recording", "SensorModel", "open_recording", "read_recording", "synthesize",
           "truth_path", "write_recording", "write_truth"]
