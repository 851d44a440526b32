"""NI TDMS recordings (through ``nptdms``), read block by block.

The file's metadata (the segments' object lists and the properties) is read once, by
``nptdms.TdmsFile.open``, when it is opened.  Each lane's values are then located: runs of pieces at
regular byte offsets (one run per raw-data chunk layout; segments laid out alike, as a logger writes
them, merge into one run), so nothing per segment is kept and a block of rows is a few reads per lane
whatever the size or number of the segments.  This holds for plain data: numbers of a fixed size,
contiguous or interleaved, little- or big-endian, a last segment cut short.  nptdms's own channel
slices read whole raw-data chunks (a file written as one segment would be read whole for every
slice), so they are used only for the rest (DAQmx raw data, scaled channels), block by block.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import numpy as np

from fruitimpact.signals.read.common import (
    BLOCK_SAMPLES,
    FORCE_UNITS,
    RATE_TOLERANCE,
    RecordingSource,
    agree,
    check_finite,
    error,
    need_rate,
    open_file,
    read_some,
)

# Table-of-contents flags of a segment's lead-in (the TDMS file format; nptdms.common.toc_properties).
_INTERLEAVED, _BIG_ENDIAN, _DAQMX = 1 << 5, 1 << 6, 1 << 7


def _property_number(path, name: str, properties, key: str):
    if key not in properties:
        return None
    value = properties[key]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not np.isfinite(float(value)):
        raise error(path, f"channel {name!r}: property {key} = {value!r} is not a finite number")
    return float(value)


def _nptdms(path):
    try:
        from nptdms import TdmsFile
    except ImportError:
        raise error(path, "reading TDMS needs the nptdms package (pip install nptdms)") from None
    return TdmsFile


class _NptdmsLog:
    """While open, nptdms's log records are kept here instead of printed (two multi-line warnings on stderr for a
    file cut short, in nptdms's words): ``notes()`` says them once, in ours."""

    def __enter__(self):
        import logging

        self.records = []
        handler = logging.Handler(logging.WARNING)
        handler.emit = self.records.append
        # nptdms gives each of its modules a logger with its own handler (nptdms.reader, nptdms.tdms_segment …)
        names = ["nptdms"] + [name for name in logging.Logger.manager.loggerDict if name.startswith("nptdms.")]
        self.saved = []
        for name in names:
            logger = logging.getLogger(name)
            self.saved.append((logger, logger.propagate, list(logger.handlers)))
            logger.propagate, logger.handlers = False, [handler]
        return self

    def __exit__(self, *exc):
        for logger, propagate, handlers in self.saved:
            logger.propagate, logger.handlers = propagate, handlers
        return False

    def notes(self) -> tuple[str, ...]:
        texts = [record.getMessage() for record in self.records]
        notes = []
        if any("less data than expected" in text or "not a multiple of the chunk size" in text for text in texts):
            notes.append("the last segment is cut short (the file was truncated, or is still being written): its "
                         "complete samples are read, the rest of it is not")
        notes += [f"nptdms: {' '.join(text.split())}" for text in texts
                  if "less data than expected" not in text and "not a multiple of the chunk size" not in text]
        return tuple(dict.fromkeys(notes))


def open_tdms(path: Path, rate, column) -> RecordingSource:
    """Every channel of numbers (or the ``column``) as a lane ``group/channel``; see ``signals.read``."""
    if path.stat().st_size == 0:
        raise error(path, "empty file")
    tdms_file = _nptdms(path)
    heard = _NptdmsLog()
    try:
        with heard, tdms_file.open(path) as tdms:  # the metadata stays readable once the file is closed
            # (lane name, group, channel, dtype, length, properties, the nptdms channel)
            channels = [(f"{group.name}/{channel.name}", group.name, channel.name, channel.dtype, len(channel),
                         dict(channel.properties), channel) for group in tdms.groups() for channel in group.channels()]
            segments = getattr(getattr(tdms, "_reader", None), "_segments", None)  # nptdms internals: see _plan
    except Exception as exc:  # noqa: BLE001 - nptdms raises ValueError, KeyError, struct.error … on damaged files
        raise error(path, f"not a readable TDMS file ({exc})") from None
    if not channels:
        raise error(path, "no channels (not a TDMS recording, or an empty one)")
    if column is not None:
        chosen = [c for c in channels if c[0] == column] or [c for c in channels if c[2] == column]
        if not chosen:
            raise error(path, f"unknown column {column!r} (available: {', '.join(repr(c[0]) for c in channels)})",
                        "column")
        if len(chosen) > 1:
            raise error(path, f"column {column!r} is ambiguous: it matches {', '.join(repr(c[0]) for c in chosen)}; "
                              f"give group/channel", "column")
        name, _, _, dtype, length, _, _ = chosen[0]
        if dtype.kind not in "iuf":
            raise error(path, f"channel {name!r} holds {dtype} values, not numbers", "column")
        if length == 0:
            raise error(path, f"all lanes empty: channel {name!r} has no samples")
    else:
        numeric = [c for c in channels if c[3].kind in "iuf"]
        if not numeric:
            raise error(path, f"no channel of numbers (channels: {', '.join(repr(c[0]) for c in channels)})")
        chosen = [c for c in numeric if c[4] > 0]
        if not chosen:
            raise error(path, "all lanes empty: no channel has samples")
    scales, rates, starts, lengths, clips = {}, {}, {}, {}, {}
    for name, _, _, _, length, properties, _ in chosen:
        unit = str(properties.get("unit_string", "")).strip()
        if unit and unit not in FORCE_UNITS:
            raise error(path, f"channel {name!r} has unit {unit!r}; a force lane must be in N, kN or mN "
                              f"(or carry no unit_string, read as N)")
        scales[name] = FORCE_UNITS.get(unit, 1.0)
        x_unit = str(properties.get("wf_xunit_string", "s")).strip()
        if x_unit not in ("s", ""):
            raise error(path, f"channel {name!r}: waveform time unit {x_unit!r} is not allowed (allowed: s)")
        increment = _property_number(path, name, properties, "wf_increment")
        if increment is not None and increment <= 0.0:
            raise error(path, f"channel {name!r}: wf_increment = {increment!r} must be > 0 s")
        rates[name] = None if increment is None else 1.0 / increment
        starts[name] = _property_number(path, name, properties, "wf_start_offset") or 0.0
        low, high = (_property_number(path, name, properties, key) for key in ("clip_low", "clip_high"))
        clips[name] = (None if low is None else low * scales[name], None if high is None else high * scales[name])
        lengths[name] = length
    advice = "; read one lane with column="

    def listing(mapping):
        return ", ".join(f"{name!r}: {value!r}" for name, value in mapping.items())

    if len(set(lengths.values())) > 1:
        raise error(path, f"lanes differ in length ({listing(lengths)}){advice}")
    known = {name: value for name, value in rates.items() if value is not None}
    if known and len(known) < len(rates):
        raise error(path, f"some channels have no wf_increment ({', '.join(n for n in rates if n not in known)})"
                          f"{advice}")
    if known:
        first = next(iter(known.values()))
        if any(abs(value - first) > RATE_TOLERANCE * first for value in known.values()):
            raise error(path, f"lanes differ in rate ({listing(known)} Hz){advice}")
        rate = agree(path, first, rate, "the file's wf_increment")
    else:
        rate = need_rate(path, rate, "the channels have no wf_increment")
    if len(set(starts.values())) > 1:
        raise error(path, f"lanes differ in wf_start_offset ({listing(starts)} s){advice}")
    if len(set(clips.values())) > 1:
        raise error(path, f"lanes differ in clip_low/clip_high ({listing(clips)} N){advice}")
    clip_low, clip_high = next(iter(clips.values()))
    names = tuple(c[0] for c in chosen)
    samples = next(iter(lengths.values()))
    # each lane: its unit's scale, and where its values are (None: read through nptdms)
    lanes = [(c[1], c[2], scales[c[0]], _plan(segments, c[6])) for c in chosen]
    del tdms, segments, channels, chosen  # nptdms's metadata (objects per segment) is not kept

    def blocks(hint: int):
        return _blocks(path, names, lanes, samples, max(hint, BLOCK_SAMPLES))

    return RecordingSource(source=str(path), format="tdms", rate=rate, lane_names=names,
                           start_time=next(iter(starts.values())), clip_low=clip_low, clip_high=clip_high,
                           samples=samples, notes=heard.notes(), _blocks=blocks)


# --------------------------------------------------------------------------- reading the samples

class _NotPlain(Exception):
    """A segment whose raw data is not at fixed byte offsets (DAQmx, unsized types)."""


class _Run(NamedTuple):
    """``pieces`` pieces of ``count`` values of a lane: value i of piece p is at byte
    start + p·step + shift + i·stride; ``start`` is where the piece's chunk (contiguous) or first row
    (interleaved) begins, so a read from there takes the other lanes' values beside it too."""

    start: int
    shift: int
    count: int
    stride: int
    pieces: int
    step: int
    dtype: np.dtype


def _plan(segments, channel) -> list[_Run] | None:
    """Where a channel's values are, in order, segments laid out alike merged into one run; None when
    nptdms must read it (scaled, DAQmx, unsized types, or nptdms's internals not as expected).
    ``segments``: nptdms's list of the file's segments."""
    try:
        if segments is None or getattr(channel, "_scaling", True) is not None:
            return None
        runs: list[_Run] = []
        for segment in segments:
            for run in _segment_runs(segment, channel.path):
                last = runs[-1] if runs else None
                if last is not None and run.pieces == 1 and (last.shift, last.count, last.stride, last.dtype) == \
                        (run.shift, run.count, run.stride, run.dtype):
                    step = last.step if last.pieces > 1 else run.start - last.start
                    if step >= run.shift + (run.count - 1) * run.stride + run.dtype.itemsize and \
                            run.start == last.start + last.pieces * step:
                        runs[-1] = last._replace(pieces=last.pieces + 1, step=step)
                        continue
                runs.append(run)
    except (_NotPlain, AttributeError, TypeError, KeyError):
        return None
    if sum(run.count * run.pieces for run in runs) != len(channel):
        return None
    return runs


def _segment_runs(segment, channel_path: str):
    """The runs of one segment: one of its raw-data chunks (contiguous: the channel's values at the
    same place in every chunk; a last chunk cut short apart), or one of all its rows (interleaved)."""
    if not segment.num_chunks:
        return
    objects = [o for o in segment.ordered_objects if o.has_data]
    target = next((o for o in objects if o.path == channel_path), None)
    if target is None or target.number_values == 0:
        return
    if segment.toc_mask & _DAQMX or any(type(o).__name__ != "TdmsSegmentObject" for o in objects):
        raise _NotPlain
    dtype = target.data_type.nptype
    if dtype is None or dtype.kind not in "iuf" or dtype.itemsize != target.data_type.size:
        raise _NotPlain
    dtype = np.dtype(dtype).newbyteorder(">" if segment.toc_mask & _BIG_ENDIAN else "<")
    override = segment.final_chunk_lengths_override
    chunks = segment.num_chunks
    if segment.toc_mask & _INTERLEAVED:
        if any(o.data_type.size is None for o in objects):
            raise _NotPlain
        width = sum(o.data_type.size for o in objects)
        shift = sum(o.data_type.size for o in objects[:objects.index(target)])
        rows = target.number_values * chunks if override is None else \
            target.number_values * (chunks - 1) + override.get(channel_path, 0)
        if rows:
            yield _Run(segment.data_position, shift, rows, width, 1, rows * width, dtype)
        return
    size = sum(o.data_size for o in objects)  # bytes of one chunk
    whole = chunks if override is None else chunks - 1
    shift = 0
    for o in objects:
        if o is target:
            break
        shift += o.data_size
    if whole:
        yield _Run(segment.data_position, shift, target.number_values, dtype.itemsize, whole, size, dtype)
    if override is not None:  # the last chunk, cut short: each object's values are fewer
        position = segment.data_position + whole * size
        shift = 0
        for o in objects:
            count = override.get(o.path, 0)
            if o is target:
                if count:
                    yield _Run(position, shift, count, dtype.itemsize, 1, size, dtype)
                break
            if count == o.number_values:
                shift += o.data_size
            elif o.data_type.size is not None:
                shift += o.data_type.size * count
            else:
                raise _NotPlain


#: Most bytes read at once to take several short pieces of a lane (with the other lanes' bytes between).
_SPAN_BYTES = 1 << 22


def _read_at(handle, path, position: int, size: int) -> bytes:
    """Up to ``size`` bytes of the file from byte ``position``."""
    try:
        handle.seek(position)
    except OSError as exc:
        raise error(path, exc.strerror or str(exc)) from None
    return read_some(handle, path, size)


class _Window:
    """Reads of the file shared by the lanes: the last two are kept, so the lanes after the first find
    their values in what the first one read (interleaved rows, chunks of small segments)."""

    def __init__(self, handle, path):
        self.handle, self.path, self.kept = handle, path, []

    def get(self, position: int, size: int, origin: int, length: int) -> memoryview:
        """Bytes [position, position + size) of the file; when not kept, read from ``origin`` (≤ position)
        ``length`` bytes or up to the end of the file, whichever is less, but at least to position + size."""
        for start, data in self.kept:
            if start <= position and position + size <= start + len(data):
                return data[position - start:position - start + size]
        data = memoryview(_read_at(self.handle, self.path, origin, max(length, position + size - origin)))
        if len(data) < position + size - origin:
            raise error(self.path, f"the file ends at byte {origin + len(data)}, before byte {position + size} its "
                                   f"metadata promises (truncated, or changed since it was opened)")
        self.kept = self.kept[-1:] + [(origin, data)]
        return data[position - origin:position - origin + size]


def _read_runs(window: _Window, runs: list[_Run], block: int):
    """The values of ``runs`` (their own dtype), in arrays of at most ``block`` values and about
    ``_SPAN_BYTES`` read: a long piece in parts, short pieces several at once (one read, a strided view)."""
    for run in runs:
        item = run.dtype.itemsize
        part = max(1, min(block, _SPAN_BYTES // run.stride))  # values of a long piece read at once
        if run.count > part:
            for piece in range(run.pieces):
                for first in range(0, run.count, part):
                    n = min(part, run.count - first)
                    rows = run.start + piece * run.step + first * run.stride  # interleaved: where the rows begin
                    position, size = rows + run.shift, (n - 1) * run.stride + item
                    data = window.get(position, size, rows, n * run.stride) if run.stride > item else \
                        window.get(position, size, position, size)
                    yield np.ndarray((n,), run.dtype, data, 0, (run.stride,))
            continue
        together = max(1, min(block // run.count, _SPAN_BYTES // run.step))
        for first in range(0, run.pieces, together):
            m = min(together, run.pieces - first)
            origin = run.start + first * run.step
            position, size = origin + run.shift, (m - 1) * run.step + (run.count - 1) * run.stride + item
            # the other lanes' values between the pieces are read too, unless that is much more than these
            data = window.get(position, size, origin, m * run.step) if run.step <= _SPAN_BYTES else \
                window.get(position, size, position, size)
            yield np.ndarray((m, run.count), run.dtype, data, 0, (run.step, run.stride)).reshape(-1)


def _blocks(path, names: tuple[str, ...], lanes: list[tuple], samples: int, block: int):
    """Blocks of ``block`` rows (the last one shorter): each lane's values × its unit's scale [N]."""
    handle, tdms, streams = None, None, []
    try:
        for group, channel_name, scale, runs in lanes:
            if runs is not None:
                if handle is None:
                    handle = open_file(path)
                    window = _Window(handle, path)
                streams.append(_Lane(_read_runs(window, runs, block), scale))
                continue
            if tdms is None:
                try:
                    tdms = _nptdms(path).open(path)
                except Exception as exc:  # noqa: BLE001 - as in open_tdms
                    raise error(path, f"not a readable TDMS file ({exc})") from None
            channel = tdms[group][channel_name]
            if len(channel) != samples:
                raise error(path, f"channel {group}/{channel_name} now has {len(channel)} samples, not {samples} "
                                  f"(the file changed since it was opened)")
            streams.append(_Lane(_sliced(path, channel, samples, block), scale))
        for start in range(0, samples, block):
            out = np.empty((min(block, samples - start), len(lanes)))
            for k, lane in enumerate(streams):
                filled = lane.fill(out[:, k])
                if filled < out.shape[0]:
                    raise error(path, f"not a readable TDMS file (the data of lane {names[k]!r} ends after "
                                      f"{start + filled} of {samples} samples)")
            check_finite(path, names, out, start)
            yield out
    finally:
        if handle is not None:
            handle.close()
        if tdms is not None:
            tdms.close()


class _Lane:
    """One lane's values [N]: its arrays (raw numbers of any dtype) taken in runs into output columns."""

    def __init__(self, arrays, scale: float):
        self.arrays, self.scale = arrays, scale
        self.current, self.used = None, 0

    def fill(self, column: np.ndarray) -> int:
        """Fill ``column`` with the next values × scale (computed in float64); the count filled (less
        than its length only when the values run out)."""
        filled = 0
        while filled < column.size:
            if self.current is None or self.used == self.current.size:
                self.current, self.used = next(self.arrays, None), 0
                if self.current is None:
                    return filled
            count = min(column.size - filled, self.current.size - self.used)
            np.multiply(self.current[self.used:self.used + count], self.scale, out=column[filled:filled + count],
                        dtype=np.float64)
            filled += count
            self.used += count
        return filled


def _sliced(path, channel, samples: int, block: int):
    """A channel read through nptdms, ``block`` values at a time (scaled by nptdms when it has a scaling)."""
    for start in range(0, samples, block):
        try:
            values = channel.read_data(start, block)
        except Exception as exc:  # noqa: BLE001 - as in open_tdms
            raise error(path, f"not a readable TDMS file ({exc})") from None
        yield np.asarray(values)


__all__ = ["open_tdms"]
