"""NumPy ``.npy`` and raw float32 recordings, read block by block with ordinary reads.

The ``.npy`` header is checked by ``numpy.load(mmap_mode="r")`` (shape, dtype, order, and that the
file holds every sample it promises); the samples are then read with plain buffered reads, not
through the map: pages of a map that has been read stay in the process's resident memory, so
iterating a 1 GB file through a map would show 1 GB resident.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np

from fruitimpact.signals.read.common import BLOCK_SAMPLES, RecordingSource, check_finite, error, need_rate, open_file, read_exactly, select
from fruitimpact.signals.settings import MAX_LANES


def open_npy(path: Path, rate, column) -> RecordingSource:
    """A 1-D (one lane) or 2-D (samples × lanes) array of integers or floats; ``rate`` required."""
    if path.stat().st_size == 0:
        raise error(path, "empty file")
    try:
        array = np.load(path, mmap_mode="r", allow_pickle=False)
    except Exception as exc:  # noqa: BLE001 - numpy raises ValueError, OSError, EOFError … on foreign content
        raise error(path, f"not a NumPy .npy file ({str(exc).splitlines()[0] if str(exc) else type(exc).__name__})") \
            from None
    if not isinstance(array, np.ndarray):
        if hasattr(array, "close"):
            array.close()
        raise error(path, "a .npz archive, not a .npy array")
    dtype, shape, offset = array.dtype, array.shape, int(getattr(array, "offset", 0))
    fortran = array.ndim == 2 and not array.flags.c_contiguous
    del array  # the map is not used for the samples
    if dtype.kind not in "iuf":
        raise error(path, f"holds {dtype} values; a recording needs real numbers (integers or floats)")
    if len(shape) not in (1, 2):
        raise error(path, f"array of shape {shape}; allowed: 1-D (one lane) or 2-D (samples × lanes)")
    width = 1 if len(shape) == 1 else shape[1]
    if width == 0:
        raise error(path, f"array of shape {shape} has no lanes")
    rate = need_rate(path, rate, ".npy files hold no time")
    if shape[0] == 0:
        raise error(path, f"all lanes empty (array of shape {shape})")
    return _source(path, "npy", rate, column, offset, dtype, shape[0], width, fortran)


def open_f32(path: Path, rate, column, lanes: int) -> RecordingSource:
    """Raw little-endian float32, ``lanes`` lanes interleaved sample by sample; ``rate`` required."""
    size = path.stat().st_size
    if size == 0:
        raise error(path, "empty file")
    if size % (4 * lanes):
        raise error(path, f"{size} bytes is not a whole number of float32 samples × {lanes} lane(s) "
                          f"(a multiple of {4 * lanes} bytes)")
    rate = need_rate(path, rate, "raw float32 files hold no time")
    return _source(path, "f32", rate, column, 0, np.dtype("<f4"), size // (4 * lanes), lanes, False)


def _source(path, kind, rate, column, offset, dtype, rows, width, fortran) -> RecordingSource:
    names = [f"lane{k}" for k in range(width)]
    selected = select(path, names, column)
    if len(selected) > MAX_LANES:
        raise error(path, f"{len(selected)} lanes (an array of {rows} samples × {width} lanes), at most {MAX_LANES}: "
                          f"a recording is samples × lanes (transposed?), or choose one lane (--column, column=)")
    indices = [names.index(name) for name in selected]
    blocks = partial(_blocks, path, offset, dtype, rows, width, fortran, indices, tuple(selected))
    first = blocks(0)
    next(first)  # the first block's samples checked (finite) before any work, as a CSV's first rows are
    first.close()
    return RecordingSource(source=str(path), format=kind, rate=rate, lane_names=tuple(selected), samples=rows,
                           _blocks=blocks)


def _blocks(path, offset: int, dtype: np.dtype, rows: int, width: int, fortran: bool, indices: list[int],
            names: tuple[str, ...], hint: int):
    """Blocks of max(hint, BLOCK_SAMPLES) rows of the lanes ``indices`` of a rows × width array of
    ``dtype`` stored from byte ``offset`` (row-major, or column-major when ``fortran``), as float64."""
    block = max(hint, BLOCK_SAMPLES)
    item = dtype.itemsize
    with open_file(path) as handle:
        for start in range(0, rows, block):
            count = min(block, rows - start)
            if fortran:
                out = np.empty((count, len(indices)))
                for j, k in enumerate(indices):
                    data = read_exactly(handle, path, offset + (k * rows + start) * item, count * item)
                    out[:, j] = np.frombuffer(data, dtype)
            else:
                data = read_exactly(handle, path, offset + start * width * item, count * width * item)
                raw = np.frombuffer(data, dtype).reshape(count, width)
                out = raw.astype(np.float64) if len(indices) == width else raw[:, indices].astype(np.float64)
            del data
            check_finite(path, names, out, start)
            yield out


__all__ = ["open_f32", "open_npy"]
