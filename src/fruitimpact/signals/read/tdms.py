"""NI TDMS recordings (through ``nptdms``), read block by block.

The file is opened with ``nptdms.TdmsFile.open``, which reads only the metadata (the segments'
object lists and the properties).  Samples are then read straight from the segments' raw data:
for a plain segment (values of a fixed-size number type, contiguous or interleaved, not DAQmx, no
scaling) every channel's values are at known byte offsets, so a block of rows is one read per lane
whatever the size of the segment.  nptdms's own channel slices read whole raw-data chunks (a file
written as one segment would be read whole for every slice), so they are used only for what is
not plain (DAQmx raw data, scaled channels), block by block.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .common import (
    BLOCK_SAMPLES,
    FORCE_UNITS,
    RATE_TOLERANCE,
    RecordingSource,
    agree,
    check_finite,
    error,
    need_rate,
    open_file,
    read_exactly,
)

# Table-of-contents flags of a segment's lead-in (the TDMS file format; nptdms.common.toc_properties).
_RAW_DATA, _INTERLEAVED, _BIG_ENDIAN, _DAQMX = 1 << 3, 1 << 5, 1 << 6, 1 << 7
#: Buffer of each lane's file handle [bytes]: small segments are served from it without a system call.
_LANE_BUFFER = 1 << 18


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


def open_tdms(path: Path, rate, column) -> RecordingSource:
    """Every channel of numbers (or the ``column``) as a lane ``group/channel``; see ``signals.read``."""
    if path.stat().st_size == 0:
        raise error(path, "empty file")
    tdms_file = _nptdms(path)
    try:
        with tdms_file.open(path) as tdms:
            # (lane name, group, channel, dtype, length, properties)
            channels = [(f"{group.name}/{channel.name}", group.name, channel.name, channel.dtype, len(channel),
                         dict(channel.properties)) for group in tdms.groups() for channel in group.channels()]
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
        name, _, _, dtype, length, _ = chosen[0]
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
    for name, _, _, _, length, properties in chosen:
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
    lanes = [(c[1], c[2], scales[c[0]]) for c in chosen]
    samples = next(iter(lengths.values()))

    def blocks(hint: int):
        return _blocks(path, names, lanes, samples, max(hint, BLOCK_SAMPLES))

    return RecordingSource(source=str(path), format="tdms", rate=rate, lane_names=names,
                           start_time=next(iter(starts.values())), clip_low=clip_low, clip_high=clip_high,
                           samples=samples, _blocks=blocks)


# --------------------------------------------------------------------------- reading the samples

class _NotPlain(Exception):
    """A segment whose raw data is not at fixed byte offsets (DAQmx, unsized types, scaling)."""


def _blocks(path, names: tuple[str, ...], lanes: list[tuple[str, str, float]], samples: int, block: int):
    """Blocks of ``block`` rows (the last one shorter): each lane's values × its unit's scale [N]."""
    tdms_file = _nptdms(path)
    try:
        tdms = tdms_file.open(path)
    except Exception as exc:  # noqa: BLE001 - as in open_tdms
        raise error(path, f"not a readable TDMS file ({exc})") from None
    handles = []
    try:
        streams = []
        for group, channel_name, scale in lanes:
            channel = tdms[group][channel_name]
            if len(channel) != samples:
                raise error(path, f"channel {group}/{channel_name} now has {len(channel)} samples, not {samples} "
                                  f"(the file changed since it was opened)")
            pieces = _plain_pieces(tdms, channel)
            if pieces is None:
                streams.append(_Lane(_sliced(path, channel, samples, block), scale))
            else:
                handles.append(open_file(path, buffering=_LANE_BUFFER))
                streams.append(_Lane(_read_pieces(handles[-1], path, pieces, block), scale))
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
        for handle in handles:
            handle.close()
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


def _plain_pieces(tdms, channel):
    """The channel's raw data as pieces (byte offset of the first value, values, bytes from one value
    to the next, dtype) when every segment holding it is plain and they hold all its values; else None."""
    try:
        if getattr(channel, "_scaling", True) is not None:
            return None
        segments = tdms._reader._segments
        total = 0
        for segment in segments:  # a first pass to check, without keeping anything
            for _, count, _, _ in _segment_pieces(segment, channel.path):
                total += count
    except (_NotPlain, AttributeError, TypeError, KeyError):
        return None
    if total != len(channel):
        return None
    return (piece for segment in segments for piece in _segment_pieces(segment, channel.path))


def _segment_pieces(segment, channel_path: str):
    """The pieces of one segment: one per raw-data chunk (contiguous), or one for the whole segment
    (interleaved: rows of every channel's value)."""
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
    last = segment.num_chunks - 1
    if segment.toc_mask & _INTERLEAVED:
        if any(o.data_type.size is None for o in objects):
            raise _NotPlain
        width = sum(o.data_type.size for o in objects)
        shift = sum(o.data_type.size for o in objects[:objects.index(target)])
        rows = target.number_values * segment.num_chunks if override is None else \
            target.number_values * last + override.get(channel_path, 0)
        yield segment.data_position + shift, rows, width, dtype
        return
    chunk = sum(o.data_size for o in objects)
    for index in range(segment.num_chunks):
        position = segment.data_position + index * chunk
        final = override is not None and index == last
        for o in objects:
            count = override.get(o.path, 0) if final else o.number_values
            if o is target:
                if count:
                    yield position, count, dtype.itemsize, dtype
                break
            if count == o.number_values:
                position += o.data_size
            elif o.data_type.size is not None:
                position += o.data_type.size * count
            else:
                raise _NotPlain


def _read_pieces(handle, path, pieces, block: int):
    """The values of ``pieces`` (their own dtype), in arrays of at most ``block`` values."""
    for position, count, stride, dtype in pieces:
        for start in range(0, count, block):
            n = min(block, count - start)
            size = (n - 1) * stride + dtype.itemsize
            data = read_exactly(handle, path, position + start * stride, size)
            if stride == dtype.itemsize:
                yield np.frombuffer(data, dtype)
            else:  # interleaved: every stride-th bytes
                yield np.ndarray((n,), dtype, data, 0, (stride,))


__all__ = ["open_tdms"]
