"""Reading force recordings (issue 8, item 1; issue 13, item 4): ``Recording``, ``signals.read_recording``
and ``signals.read.open_recording`` (the same reading, chunk by chunk, in memory bounded by the chunk).

References: files written here by hand (CSV text, ``numpy.save``, raw bytes
from ``numpy.tofile``, ``nptdms.TdmsWriter``, TDMS segments written byte by byte
from the file format) with values chosen in the test, and the example TDMS files
that ship inside the nptdms wheel (``nptdms/test/data``, written by LabVIEW /
DAQmx), whose expected values are those asserted by npTDMS's own tests
(``nptdms/test/test_example_files.py``) or read by nptdms itself
(``TdmsFile.read``).  Round trips go through ``signals.synth.write_recording``;
CSV floats are written as shortest round-trip decimals, so they read back
bit-identical; float32 files read back as the float32 rounding of the values,
exactly.  Chunked reading is held to ``read_recording`` bit for bit, for every
chunk size.
"""

from __future__ import annotations

import importlib.resources
import math
import struct
import tracemalloc

import numpy as np
import pytest

from fruitimpact.signals import Recording, read_recording, write_recording
from fruitimpact.signals.read import RecordingSource, csvtable, open_recording

RNG = np.random.default_rng(8)


def _recording(lanes=2, samples=500, rate=20000.0, start_time=0.25, **kwargs):
    data = {f"force{k}": RNG.normal(10.0 * k, 3.0, samples) for k in range(lanes)}
    return Recording(rate=rate, lanes=data, start_time=start_time, **kwargs)


def _write(path, text: str, encoding="utf-8"):
    path.write_bytes(text.encode(encoding))
    return path


def _refused(match, path, **kwargs):
    with pytest.raises(ValueError, match=match) as info:
        read_recording(path, **kwargs)
    assert "\n" not in str(info.value)
    return str(info.value)


# --------------------------------------------------------------------------- Recording

def test_recording_fields_and_time():
    rec = Recording(rate=1000.0, lanes={"a": [1, 2, 3], "b": np.zeros(3)}, start_time=2.0)
    assert rec.samples == 3 and rec.duration == pytest.approx(3e-3) and rec.lane_names == ("a", "b")
    np.testing.assert_array_equal(rec.time(), [2.0, 2.001, 2.002])
    assert rec.lanes["a"].dtype == np.float64 and not rec.lanes["a"].flags.writeable
    with pytest.raises(TypeError):
        rec.lanes["c"] = np.zeros(3)


def test_recording_copies_the_callers_array():
    values = np.arange(4.0)
    rec = Recording(rate=10.0, lanes={"a": values})
    values[0] = 99.0
    assert rec.lanes["a"][0] == 0.0 and values.flags.writeable


@pytest.mark.parametrize("kwargs,match", [
    ({"rate": 0.0, "lanes": {"a": [1.0]}}, "rate must be a finite number > 0"),
    ({"rate": math.nan, "lanes": {"a": [1.0]}}, "rate must be a finite number > 0"),
    ({"rate": 10.0, "lanes": {}}, "lanes must be a non-empty mapping"),
    ({"rate": 10.0, "lanes": {"a": [1.0, 2.0], "b": [1.0]}}, "same length; lane 'b' has 1"),
    ({"rate": 10.0, "lanes": {"a": [1.0, math.nan]}}, "sample 1 of lane 'a' is nan"),
    ({"rate": 10.0, "lanes": {"a": []}}, "no samples"),
    ({"rate": 10.0, "lanes": {"a": [[1.0]]}}, "must be 1-D"),
    ({"rate": 10.0, "lanes": {"a": [1.0]}, "clip_low": 5.0, "clip_high": 1.0}, "clip_low must be below clip_high"),
])
def test_recording_refuses(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Recording(**kwargs)


# --------------------------------------------------------------------------- round trips

def test_round_trip_csv_is_exact(tmp_path):
    rec = _recording(lanes=3)
    got = read_recording(write_recording(rec, tmp_path / "r.csv"))
    assert got.lane_names == rec.lane_names
    for name in rec.lane_names:
        np.testing.assert_array_equal(got.lanes[name], rec.lanes[name])  # shortest round-trip decimals
    # the rate is derived from the written times (start + n/rate, each rounded to double): 1e-12
    assert got.rate == pytest.approx(rec.rate, rel=1e-12)
    assert got.start_time == rec.start_time and got.samples == rec.samples
    assert (tmp_path / "r.csv").read_text().splitlines()[0] == "time [s],force0 [N],force1 [N],force2 [N]"


def test_round_trip_npy(tmp_path):
    rec = _recording(lanes=2)
    got = read_recording(write_recording(rec, tmp_path / "r.npy"), rate=rec.rate)
    assert got.lane_names == ("lane0", "lane1") and got.rate == rec.rate and got.start_time == 0.0
    for k, name in enumerate(rec.lane_names):
        np.testing.assert_array_equal(got.lanes[f"lane{k}"], rec.lanes[name])
    one = read_recording(write_recording(_recording(lanes=1), tmp_path / "one.npy"), rate=5.0)
    assert one.lane_names == ("lane0",) and np.load(tmp_path / "one.npy").ndim == 1


@pytest.mark.parametrize("suffix", [".f32", ".bin", ".raw"])
def test_round_trip_raw_float32_interleaved(tmp_path, suffix):
    rec = _recording(lanes=3)
    path = write_recording(rec, tmp_path / f"r{suffix}")
    assert path.stat().st_size == 4 * 3 * rec.samples
    got = read_recording(path, rate=rec.rate, lanes=3)
    for k, name in enumerate(rec.lane_names):
        # float32 precision: exactly the float32 rounding of each value
        np.testing.assert_array_equal(got.lanes[f"lane{k}"], rec.lanes[name].astype(np.float32).astype(float))
    raw = np.fromfile(path, dtype="<f4")
    assert raw[1] == np.float32(rec.lanes["force1"][0])  # interleaved sample by sample


def test_round_trip_tdms(tmp_path):
    rec = _recording(lanes=2, clip_low=-250.0, clip_high=250.0)
    got = read_recording(write_recording(rec, tmp_path / "r.tdms"))
    assert got.lane_names == ("fruitimpact/force0", "fruitimpact/force1")
    for name in rec.lane_names:
        np.testing.assert_array_equal(got.lanes["fruitimpact/" + name], rec.lanes[name])
    assert got.rate == pytest.approx(rec.rate, rel=1e-15)  # 1/(1/rate) in doubles
    assert got.start_time == rec.start_time and (got.clip_low, got.clip_high) == (-250.0, 250.0)
    one = read_recording(tmp_path / "r.tdms", column="force1")
    assert one.lane_names == ("fruitimpact/force1",)


def test_format_overrides_the_extension(tmp_path):
    rec = _recording(lanes=1)
    path = write_recording(rec, tmp_path / "r.dat", format="csv")
    got = read_recording(path, format="csv")
    np.testing.assert_array_equal(got.lanes["force0"], rec.lanes["force0"])
    assert read_recording(path, format=".txt").samples == rec.samples


# --------------------------------------------------------------------------- CSV variants

def test_csv_milliseconds_units_and_preamble(tmp_path):
    path = _write(tmp_path / "a.csv", "# exported by a test\n#  rate 1 kHz\n\n"
                                      "t (ms),left [kN],right_mN,middle\n"
                                      "10,0.001,1000,1\n11,0.002,2000,2\n12,0.003,3000,3\n")
    rec = read_recording(path)
    assert rec.lane_names == ("left", "right", "middle")
    assert rec.rate == pytest.approx(1000.0, rel=1e-12) and rec.start_time == pytest.approx(0.010, rel=1e-15)
    np.testing.assert_allclose(rec.lanes["left"], [1.0, 2.0, 3.0], rtol=1e-15)    # kN -> N
    np.testing.assert_allclose(rec.lanes["right"], [1.0, 2.0, 3.0], rtol=1e-15)   # mN -> N
    np.testing.assert_array_equal(rec.lanes["middle"], [1.0, 2.0, 3.0])           # no unit: N


@pytest.mark.parametrize("header,scale", [("time [s]", 1.0), ("time_ms", 1e-3), ("Time [us]", 1e-6),
                                          ("t [\u00b5s]", 1e-6), ("TIME (s)", 1.0)])
def test_csv_time_units(tmp_path, header, scale):
    path = _write(tmp_path / "a.csv", f"{header},f [N]\n0,1\n5,2\n10,3\n")
    rec = read_recording(path)
    assert rec.rate == pytest.approx(1.0 / (5 * scale), rel=1e-12)


def test_csv_rate_only_one_column(tmp_path):
    path = _write(tmp_path / "a.txt", "force [N]\n1.5\n-2\n3e-1\n")
    rec = read_recording(path, rate=500.0)
    assert rec.lane_names == ("force",) and rec.rate == 500.0 and rec.start_time == 0.0
    np.testing.assert_array_equal(rec.lanes["force"], [1.5, -2.0, 0.3])


@pytest.mark.parametrize("delimiter", ["\t", ";"])
def test_csv_other_delimiters(tmp_path, delimiter):
    path = _write(tmp_path / "a.txt", delimiter.join(["time [s]", "a", "b [N]"]) + "\n"
                  + "\n".join(delimiter.join(map(str, row)) for row in [(0, 1, 2), (0.5, 3, 4)]) + "\n")
    rec = read_recording(path)
    assert rec.rate == 2.0 and rec.lane_names == ("a", "b")
    np.testing.assert_array_equal(rec.lanes["b"], [2.0, 4.0])


def test_csv_bom_crlf_quotes_comments_between_rows(tmp_path):
    text = '\ufefftime [s],"force [N]"\r\n0,1\r\n# pause\r\n\r\n0.25,"2"\r\n0.5,3\r\n'
    rec = read_recording(_write(tmp_path / "a.csv", text))
    assert rec.lane_names == ("force",) and rec.rate == 4.0
    np.testing.assert_array_equal(rec.lanes["force"], [1.0, 2.0, 3.0])


def test_csv_column_selection_and_agreeing_rate(tmp_path):
    path = _write(tmp_path / "a.csv", "time [s],a [N],b [kN]\n0,1,1\n0.001,2,2\n0.002,3,3\n")
    assert read_recording(path, column="b").lane_names == ("b",)
    np.testing.assert_array_equal(read_recording(path, column="b [kN]").lanes["b"], [1e3, 2e3, 3e3])
    rec = read_recording(path, rate=1000.0000001)  # agrees within 1e-6: the given rate is used
    assert rec.rate == 1000.0000001


def test_csv_uniform_within_the_tolerance_is_accepted(tmp_path):
    # intervals 0.1 s ± 5e-8 s: within 1e-6 of the mean interval
    path = _write(tmp_path / "a.csv", "time [s],f\n0,1\n0.10000005,2\n0.2,3\n0.3,4\n")
    assert read_recording(path).rate == pytest.approx(10.0, rel=1e-15)


def test_csv_large_file_fast_path(tmp_path):
    rec = _recording(lanes=2, samples=200_000)
    got = read_recording(write_recording(rec, tmp_path / "big.csv"))
    np.testing.assert_array_equal(got.lanes["force1"], rec.lanes["force1"])


# --------------------------------------------------------------------------- CSV errors

CSV_ERRORS = [
    ("time [s],f\n0,1\n0.1,2\n0.1,3\n", {}, r"non-monotonic time at row 3 \(line 4\)"),
    ("time [s],f\n0,1\n0.2,2\n0.1,3\n", {}, r"non-monotonic time at row 3 \(line 4\)"),
    ("time [s],f\n0,1\n0.1,2\n0.200001,3\n0.3,4\n", {}, r"non-uniform sampling at row 3 \(line 4\)"),
    ("time [s],f\n0,1\n0.001,2\n0.002,3\n", {"rate": 1001.0}, r"rate=1001 Hz disagrees with the time column"),
    ("time [s],f\n0,1\n0.1,nan\n", {}, r"line 3 \(data row 2\), column 'f': 'nan' is not a number"),
    ("time [s],f\n0,1\n0.1,NaN\n", {}, r"'NaN' is not a number"),
    ("time [s],f\n0,1\n0.1,\n", {}, r"line 3 \(data row 2\), column 'f': empty cell"),
    ("time [s],f\n0,1\n0.1,1.2.3\n", {}, r"'1.2.3' is not a number"),
    ("time [s],f\n0,1\n0.1,inf\n", {}, r"'inf' is not a number"),
    ("time [s],f\n0,1\n0.1,1e999\n", {}, r"'1e999' is beyond double precision"),
    ("# c\ntime [s],f\n0,1\n\n0.1,2,3\n", {}, r"line 5 has 3 cells, the header 2 \(ragged row\)"),
    ("time [s],f\n0,1\n0.1\n", {}, r"line 3 has 1 cells, the header 2 \(ragged row\)"),
    ("time,f\n0,1\n", {}, r"the time column 'time' has no unit"),
    ("time [min],f\n0,1\n", {}, r"time unit 'min' is not allowed \(allowed: s, ms, us\)"),
    ("time [s],f [V]\n0,1\n", {}, r"force unit 'V' is not allowed \(allowed: N, kN, mN"),
    ("time [s],a [N],a [kN]\n0,1,2\n", {}, r"duplicate column names 'a'"),
    ("time [s],t [ms]\n0,1\n", {}, r"more than one time column"),
    ("time [s]\n0\n", {}, r"no force column"),
    ("0,1\n0.1,2\n", {}, r"looks like data \('0'\), not a header"),
    ("time [s],,f\n0,1,2\n", {}, r"column 2 of the header has no name"),
    ("f [N]\n1\n2\n", {}, r"rate is required: the file has no time column"),
    ("time [s],f\n", {}, r"all lanes empty: the file has a header but no data rows"),
    ("time [s],f\n# no data\n\n", {}, r"all lanes empty: the file has a header but no data rows"),
    ("# only\n# comments\n\n", {}, r"empty file \(only comments and blank lines\)"),
    ("", {}, r"empty file"),
    ("time [s],f\n0,1\n", {}, r"rate is required: one sample cannot give the rate"),
    ("time [s],a,b\n0,1,2\n0.1,1,2\n", {"column": "c"}, r"unknown column 'c' \(available: 'a', 'b'\)"),
    ("time [s],a,b\n0,1,2\n0.1,1,2\n", {"column": "time"}, r"column 'time' is the time column"),
]


@pytest.mark.parametrize("text,kwargs,match", CSV_ERRORS)
def test_csv_errors(tmp_path, text, kwargs, match):
    message = _refused(match, _write(tmp_path / "bad.csv", text), **kwargs)
    assert "bad.csv" in message


def test_csv_error_only_in_an_unused_column_is_not_read(tmp_path):
    path = _write(tmp_path / "a.csv", "time [s],a,b\n0,1,x\n0.5,2,y\n")
    np.testing.assert_array_equal(read_recording(path, column="a").lanes["a"], [1.0, 2.0])
    _refused(r"column 'b': 'x' is not a number", path)


def test_csv_binary_garbage(tmp_path):
    path = tmp_path / "g.csv"
    path.write_bytes(bytes(range(256)) * 4)
    _refused(r"binary content \(NUL bytes\), not CSV text", path)
    path.write_bytes(b"time [s],f\n0,\xff\xfe\n")
    _refused(r"not UTF-8 text \(undecodable byte at offset 13\)", path)


# --------------------------------------------------------------------------- any format

def test_missing_file_folder_and_unsupported_format(tmp_path):
    _refused(r"'.*nothing\.csv': no such file", tmp_path / "nothing.csv")
    folder = tmp_path / "folder.csv"
    folder.mkdir()
    _refused(r"it is a folder, not a recording file", folder)
    _write(tmp_path / "a.xyz", "x")
    _refused(r"unsupported format \.xyz of .* \(allowed: \.csv, \.txt, \.npy, \.f32, \.bin, \.raw, \.tdms",
             tmp_path / "a.xyz")
    _refused(r"unsupported format \(no extension\)", _write(tmp_path / "noext", "x"))
    _refused(r"format must be one of csv, npy, f32, tdms", tmp_path / "a.xyz", format="wav")


@pytest.mark.parametrize("kwargs,match", [
    ({"rate": -1.0}, r"rate must be a finite number of Hz in \(0, 1e\+07\]"),
    ({"rate": math.inf}, r"rate must be a finite number of Hz in \(0, 1e\+07\]"),
    ({"rate": 1e12}, r"rate must be a finite number of Hz in \(0, 1e\+07\]"),  # buffers of terabytes
    ({"rate": True}, r"rate must be a number"),
    ({"rate": "20 parsecs"}, r"rate must be a sample rate"),
    ({"column": 3}, r"column must be a lane name"),
    ({"lanes": 0}, r"lanes must be an integer >= 1"),
    ({"lanes": 2}, r"lanes applies to raw float32 files only"),
])
def test_argument_errors_come_before_the_file(tmp_path, kwargs, match):
    _refused(match, tmp_path / "missing.csv", **kwargs)  # the argument is refused, not the missing file


# --------------------------------------------------------------------------- NPY and raw

@pytest.mark.parametrize("array,kwargs,match", [
    (np.zeros((4, 2)), {}, r"rate is required: \.npy files hold no time"),
    (np.zeros((2, 2, 2)), {"rate": 1.0}, r"array of shape \(2, 2, 2\); allowed: 1-D"),
    (np.zeros(3, dtype=complex), {"rate": 1.0}, r"holds complex128 values; a recording needs real numbers"),
    (np.array([True, False]), {"rate": 1.0}, r"holds bool values"),
    (np.array([1.0, np.nan]), {"rate": 1.0}, r"sample 1 of lane 'lane0' is nan"),
    (np.zeros(0), {"rate": 1.0}, r"all lanes empty \(array of shape \(0,\)\)"),
    (np.zeros((5, 0)), {"rate": 1.0}, r"array of shape \(5, 0\) has no lanes"),
    (np.zeros((5, 2)), {"rate": 1.0, "column": "lane2"}, r"unknown column 'lane2' \(available: 'lane0', 'lane1'\)"),
])
def test_npy_errors(tmp_path, array, kwargs, match):
    np.save(tmp_path / "a.npy", array)
    _refused(match, tmp_path / "a.npy", **kwargs)


def test_npy_garbage_empty_and_npz(tmp_path):
    _refused(r"empty file", _write(tmp_path / "e.npy", ""))
    (tmp_path / "g.npy").write_bytes(b"\x93NUMPY garbage" + bytes(50))
    _refused(r"not a NumPy \.npy file", tmp_path / "g.npy", rate=1.0)
    np.savez(tmp_path / "z.npz", a=np.zeros(3))
    (tmp_path / "z.npz").rename(tmp_path / "z.npy")
    _refused(r"a \.npz archive, not a \.npy array", tmp_path / "z.npy", rate=1.0)
    np.save(tmp_path / "o.npy", np.array([{"a": 1}], dtype=object), allow_pickle=True)
    _refused(r"not a NumPy \.npy file", tmp_path / "o.npy", rate=1.0)


def test_npy_integers_are_read(tmp_path):
    np.save(tmp_path / "i.npy", np.array([[1, 2], [3, 4]], dtype=np.int16))
    rec = read_recording(tmp_path / "i.npy", rate=100.0, column="lane1")
    np.testing.assert_array_equal(rec.lanes["lane1"], [2.0, 4.0])


def test_raw_errors(tmp_path):
    path = tmp_path / "a.f32"
    np.arange(6, dtype="<f4").tofile(path)
    _refused(r"rate is required: raw float32 files hold no time", path)
    _refused(r"24 bytes is not a whole number of float32 samples × 4 lane\(s\) \(a multiple of 16 bytes\)", path,
             rate=1.0, lanes=4)
    _refused(r"unknown column 'lane3' \(available: 'lane0', 'lane1', 'lane2'\)", path, rate=1.0, lanes=3,
             column="lane3")
    np.testing.assert_array_equal(read_recording(path, rate=1.0, lanes=3, column="lane2").lanes["lane2"], [2, 5])
    _refused(r"empty file", _write(tmp_path / "e.bin", ""), rate=1.0)
    (tmp_path / "odd.raw").write_bytes(b"abcde")
    _refused(r"5 bytes is not a whole number", tmp_path / "odd.raw", rate=1.0)
    np.array([1.0, np.inf], dtype="<f4").tofile(tmp_path / "inf.raw")
    _refused(r"sample 1 of lane 'lane0' is inf", tmp_path / "inf.raw", rate=1.0)


# --------------------------------------------------------------------------- TDMS

def _example(name: str):
    folder = importlib.resources.files("nptdms") / "test" / "data"
    path = folder / name
    if not path.is_file():
        pytest.skip(f"nptdms ships no {name} in this installation")
    return path


def test_nptdms_example_waveform_big_endian():
    # LabVIEW example (big-endian), waveform channels with wf_increment 1 ms; values from npTDMS's tests
    rec = read_recording(_example("big_endian.tdms"))
    assert rec.lane_names == ("Measured Data/Amplitude sweep", "Measured Data/Phase sweep")
    assert rec.rate == pytest.approx(1000.0, rel=1e-12) and rec.samples == 3500 and rec.start_time == 0.0
    np.testing.assert_allclose(rec.lanes["Measured Data/Phase sweep"][:5],
                               [0.0, 0.0634176, 0.1265799, 0.1892325, 0.2511234], atol=1e-7)
    assert read_recording(_example("big_endian.tdms"), column="Phase sweep").lane_names == \
        ("Measured Data/Phase sweep",)


def test_nptdms_example_raw_timestamps():
    rec = read_recording(_example("raw_timestamps.tdms"))
    assert rec.lane_names == ("Untitled/Untitled",) and rec.samples == 128
    assert rec.rate == pytest.approx(1000.0, rel=1e-12)


def test_nptdms_example_digital_input_needs_one_lane():
    path = _example("Digital_Input.tdms")
    # three groups (all data and two decimations): different lengths and rates
    _refused(r"lanes differ in length .*; read one lane with column=", path)
    _refused(r"column 'Dev1_port3_line7 - line 0' is ambiguous: it matches", path, column="Dev1_port3_line7 - line 0")
    name = "07/09/2012 06:58:23 PM - Digital Input - All Data/Dev1_port3_line7 - line 0"
    rec = read_recording(path, column=name)
    assert rec.samples == 20000 and rec.rate == pytest.approx(2000.0, rel=1e-12)
    np.testing.assert_array_equal(rec.lanes[name][:10], [0, 1, 0, 1, 0, 1, 0, 1, 0, 1])
    _refused(r"unknown column 'nope' \(available: '07/09/2012", path, column="nope")


def test_nptdms_example_daqmx_volts_is_refused():
    # DAQmx raw data with linear scaling to Volts: not a force
    _refused(r"channel 'Layer Data/First  Channel' has unit 'Volts'; a force lane must be in N, kN or mN",
             _example("raw1.tdms"))


def _tdms(path, channels, root=None):
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    with TdmsWriter(str(path)) as writer:
        writer.write_segment([RootObject(root or {}), GroupObject("daq")]
                             + [ChannelObject("daq", name, data, properties=props) for name, data, props in channels])
    return path


def test_tdms_units_clip_limits_and_skipped_channels(tmp_path):
    waveform = {"wf_increment": 5e-5, "wf_start_offset": 0.5, "wf_samples": 3}
    path = _tdms(tmp_path / "a.tdms", [
        ("kilo", np.array([0.1, 0.2, 0.3]), dict(waveform, unit_string="kN", clip_low=-0.5, clip_high=0.5)),
        ("milli", np.array([100.0, 200.0, 300.0], dtype=np.float32),
         dict(waveform, unit_string="mN", clip_low=-5e5, clip_high=5e5)),
        ("note", np.array(["a", "b", "c"]), {}),
        ("empty", np.array([], dtype=float), {}),
    ])
    rec = read_recording(path)
    assert rec.lane_names == ("daq/kilo", "daq/milli")
    np.testing.assert_allclose(rec.lanes["daq/kilo"], [100.0, 200.0, 300.0], rtol=1e-15)
    np.testing.assert_allclose(rec.lanes["daq/milli"], [0.1, 0.2, 0.3], rtol=1e-7)  # float32 data
    assert rec.rate == pytest.approx(20000.0, rel=1e-12) and rec.start_time == 0.5
    assert (rec.clip_low, rec.clip_high) == (pytest.approx(-500.0), pytest.approx(500.0))
    _refused(r"channel 'daq/note' holds object values, not numbers", path, column="note")
    _refused(r"all lanes empty: channel 'daq/empty' has no samples", path, column="empty")
    _refused(r"rate=30000 Hz disagrees with the file's wf_increment \(20000 Hz", path, rate=30000.0)


def test_tdms_without_waveform_timing_needs_rate(tmp_path):
    path = _tdms(tmp_path / "a.tdms", [("f", np.arange(4.0), {})])
    _refused(r"rate is required: the channels have no wf_increment", path)
    rec = read_recording(path, rate=100.0)
    assert rec.rate == 100.0 and rec.lane_names == ("daq/f",)


@pytest.mark.parametrize("channels,match", [
    ([("a", np.arange(3.0), {"unit_string": "V"})], r"has unit 'V'"),
    ([("a", np.arange(3.0), {"wf_increment": 1e-3}), ("b", np.arange(3.0), {"wf_increment": 2e-3})],
     r"lanes differ in rate"),
    ([("a", np.arange(3.0), {"wf_increment": 1e-3}), ("b", np.arange(3.0), {})], r"some channels have no wf_incr"),
    ([("a", np.arange(3.0), {"wf_increment": 1e-3, "wf_start_offset": 1.0}),
      ("b", np.arange(3.0), {"wf_increment": 1e-3})], r"lanes differ in wf_start_offset"),
    ([("a", np.arange(3.0), {"wf_increment": 1e-3, "clip_high": 1.0}),
      ("b", np.arange(3.0), {"wf_increment": 1e-3})], r"lanes differ in clip_low/clip_high"),
    ([("a", np.arange(3.0), {"wf_increment": -1e-3})], r"wf_increment = -0.001 must be > 0 s"),
    ([("a", np.arange(3.0), {"wf_increment": 1e-3, "wf_xunit_string": "ms"})], r"waveform time unit 'ms'"),
    ([("a", np.array([1.0, np.nan]), {"wf_increment": 1e-3})], r"sample 1 of lane 'daq/a' is nan"),
    ([("a", np.array(["x"]), {})], r"no channel of numbers \(channels: 'daq/a'\)"),
    ([("a", np.array([], dtype=float), {})], r"all lanes empty: no channel has samples"),
])
def test_tdms_errors(tmp_path, channels, match):
    _refused(match, _tdms(tmp_path / "a.tdms", channels))


def test_tdms_garbage_and_empty(tmp_path):
    _refused(r"empty file", _write(tmp_path / "e.tdms", ""))
    (tmp_path / "g.tdms").write_bytes(bytes(range(200)))
    _refused(r"not a readable TDMS file", tmp_path / "g.tdms")
    _refused(r"no channels", _tdms(tmp_path / "n.tdms", []))


# --------------------------------------------------------------------------- chunk by chunk (issue 13, item 4)

def _matrix(rec: Recording) -> np.ndarray:
    return np.column_stack([rec.lanes[name] for name in rec.lane_names])


def _joined(source: RecordingSource, samples: int) -> np.ndarray:
    """Every chunk of ``source`` checked for shape, dtype and layout, joined."""
    chunks = list(source.chunks(samples))
    for k, chunk in enumerate(chunks):
        assert chunk.dtype == np.float64 and chunk.flags.c_contiguous and chunk.ndim == 2
        assert chunk.shape[1] == len(source.lane_names)
        assert chunk.shape[0] == samples if k < len(chunks) - 1 else 1 <= chunk.shape[0] <= samples
    return np.concatenate(chunks)


def _same_as_read(path, sizes, **kwargs):
    """Chunks of every size in ``sizes`` join to exactly what read_recording returns, metadata alike."""
    rec = read_recording(path, **kwargs)
    source = open_recording(path, **kwargs)
    assert (source.rate, source.lane_names, source.start_time, source.clip_low, source.clip_high, source.source) == \
        (rec.rate, rec.lane_names, rec.start_time, rec.clip_low, rec.clip_high, rec.source)
    assert source.samples in (None, rec.samples)
    for size in sizes:
        np.testing.assert_array_equal(_joined(source, size), _matrix(rec), err_msg=f"chunks of {size}")
    return rec, source


FORMAT_CASES = [("csv", {}), ("npy", {"rate": 20000.0}), ("f32", {"rate": 20000.0, "lanes": 3}), ("tdms", {})]


@pytest.mark.parametrize("suffix,kwargs", FORMAT_CASES)
def test_chunks_of_any_size_join_to_read_recording(tmp_path, suffix, kwargs):
    rec = _recording(lanes=3, samples=5000, clip_low=-99.0, clip_high=99.0)
    path = write_recording(rec, tmp_path / f"r.{suffix}")
    got, source = _same_as_read(path, [1, 2, 7, 4096, 5000, 5001, 1 << 20], **kwargs)
    np.testing.assert_array_equal(got.lanes[got.lane_names[2]], rec.lanes["force2"].astype(
        np.float32 if suffix == "f32" else np.float64))
    assert source.samples == 5000 and source.duration == pytest.approx(0.25)
    assert source.format == suffix
    # one lane of several
    column = {"csv": "force1", "npy": "lane1", "f32": "lane1", "tdms": "force1"}[suffix]
    one, _ = _same_as_read(path, [1, 333], column=column, **kwargs)
    assert one.samples == 5000 and len(one.lane_names) == 1


def test_chunks_restart_and_refuse_a_bad_size(tmp_path):
    path = write_recording(_recording(lanes=2, samples=300), tmp_path / "r.npy")
    source = open_recording(path, rate=1000.0)
    first, second = _joined(source, 64), _joined(source, 64)
    np.testing.assert_array_equal(first, second)  # each call reads the file again
    for bad in (0, -1, 2.5, True, "64"):
        with pytest.raises(ValueError, match=r"samples must be an integer >= 1 \(samples per lane in a chunk\)"):
            source.chunks(bad)
    with pytest.raises(AttributeError):
        source.rate = 5.0  # frozen
    assert "RecordingSource(source=" in repr(source) and "lane_names=('lane0', 'lane1')" in repr(source)


def test_fortran_order_and_big_endian_npy(tmp_path):
    values = RNG.normal(0.0, 1.0, (3000, 3))
    np.save(tmp_path / "f.npy", np.asfortranarray(values))
    np.save(tmp_path / "b.npy", values.astype(">f8"))
    np.save(tmp_path / "i.npy", (values * 1000).astype(">i4"))
    for name in ("f.npy", "b.npy", "i.npy"):
        rec, _ = _same_as_read(tmp_path / name, [1, 1000, 4096], rate=100.0)
        expected = np.load(tmp_path / name).astype(np.float64)
        np.testing.assert_array_equal(_matrix(rec), expected)
    _same_as_read(tmp_path / "f.npy", [5, 3000], rate=100.0, column="lane2")


# ----------------------------------------------------------------- CSV blocks cut anywhere

CSV_TRICKY = ("\ufeff# exported by a test\n\ntime [ms];left [kN];right\r\n" + "".join(
    (f"# pause {i}\n\n" if i % 37 == 5 else "") + f"{10 + i * 0.05:.2f};{i * 1e-3:.3f};{(-1) ** i * i}\r\n"
    for i in range(900)))


@pytest.mark.parametrize("block", [1, 17, 333, 4096])
@pytest.mark.parametrize("rate_rows", [2, 3, 100, 1 << 16])
def test_csv_blocks_cutting_rows_comments_and_time_checks(tmp_path, monkeypatch, block, rate_rows):
    # milliseconds written with 2 decimals: intervals 0.05 ms exact to 1e-6 relative
    path = _write(tmp_path / "a.csv", CSV_TRICKY)
    reference = read_recording(path)
    assert reference.samples == 900 and reference.lane_names == ("left", "right")
    monkeypatch.setattr(csvtable, "BLOCK_BYTES", block)
    monkeypatch.setattr(csvtable, "RATE_ROWS", rate_rows)
    source = open_recording(path)
    assert source.rate == pytest.approx(20000.0, rel=1e-9) and source.start_time == pytest.approx(0.010)
    assert source.samples == (900 if rate_rows > 900 else None)
    for size in (1, 7, 1000) if block > 100 else (7,):
        np.testing.assert_array_equal(_joined(source, size), _matrix(reference))


def test_csv_rate_comes_from_the_first_rows(tmp_path, monkeypatch):
    # the first RATE_ROWS rows give the rate; every later interval is held to it
    monkeypatch.setattr(csvtable, "RATE_ROWS", 4)
    monkeypatch.setattr(csvtable, "BLOCK_BYTES", 16)
    path = _write(tmp_path / "a.csv", "time [s],f\n" + "".join(f"{i / 8},{i}\n" for i in range(40)))
    source = open_recording(path)
    assert source.rate == 8.0 and source.samples is None
    np.testing.assert_array_equal(_joined(source, 3)[:, 0], np.arange(40.0))


def _long_csv(rows, bad_row=None, bad_text=None):
    lines = ["# long file", "time [s],a [N],b [N]"]
    for i in range(rows):
        lines.append(bad_text if i == bad_row else f"{i / 1000:.3f},{i},{-i}")
        if i % 100 == 50:
            lines.append("# a comment between rows")
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("bad_text,match", [
    ("1.5,1,x", r"line {line} \(data row {row}\), column 'b \[N\]': 'x' is not a number"),
    ("1.5,1,nan", r"line {line} \(data row {row}\), column 'b \[N\]': 'nan' is not a number"),
    ("1.5,1,", r"line {line} \(data row {row}\), column 'b \[N\]': empty cell"),
    ("1.5,1", r"line {line} has 2 cells, the header 3 \(ragged row\)"),
    ("1.5,1,2,3", r"line {line} has 4 cells, the header 3 \(ragged row\)"),
    ("1.498,1,2", r"non-monotonic time at row {row} \(line {line}\): 1.498 s after 1.499 s"),
    ("1.5000002,1,2", r"non-uniform sampling at row {row} \(line {line}\): interval 0.0010002 s"),
])
def test_csv_errors_mid_file_name_their_line(tmp_path, monkeypatch, bad_text, match):
    monkeypatch.setattr(csvtable, "BLOCK_BYTES", 2000)
    monkeypatch.setattr(csvtable, "RATE_ROWS", 200)
    bad_row = 1500
    path = _write(tmp_path / "long.csv", _long_csv(2000, bad_row, bad_text))
    line = 3 + bad_row + (bad_row - 51) // 100 + 1  # two lines before the rows, one comment per 100 rows
    assert path.read_text().splitlines()[line - 1] == bad_text
    source = open_recording(path)  # the first rows are fine: the file opens
    assert source.samples is None and source.rate == pytest.approx(1000.0, rel=1e-9)
    seen = 0
    with pytest.raises(ValueError, match=match.format(line=line, row=bad_row + 1)) as info:
        for chunk in source.chunks(100):
            seen += chunk.shape[0]
    assert "\n" not in str(info.value) and "long.csv" in str(info.value)
    assert 1000 <= seen <= bad_row  # the chunks before the bad block came out first
    with pytest.raises(ValueError, match=match.format(line=line, row=bad_row + 1)):
        read_recording(path)


def test_csv_error_in_the_first_rows_is_refused_by_open(tmp_path):
    path = _write(tmp_path / "a.csv", _long_csv(100, 30, "0.030,1,oops"))
    with pytest.raises(ValueError, match=r"line 33 \(data row 31\), column 'b \[N\]': 'oops' is not a number"):
        open_recording(path)


def test_csv_undecodable_byte_offset_in_a_later_block(tmp_path, monkeypatch):
    monkeypatch.setattr(csvtable, "BLOCK_BYTES", 64)
    text = _long_csv(300).encode()
    position = text.index(b"0.250,250")
    path = tmp_path / "a.csv"
    path.write_bytes(text[:position] + b"\xff" + text[position + 1:])
    with pytest.raises(ValueError, match=rf"not UTF-8 text \(undecodable byte at offset {position}\)"):
        read_recording(path)
    path.write_bytes(text[:position] + b"\x00" + text[position + 1:])
    with pytest.raises(ValueError, match=r"binary content \(NUL bytes\), not CSV text"):
        read_recording(path)


def test_csv_header_after_a_long_preamble(tmp_path, monkeypatch):
    monkeypatch.setattr(csvtable, "BLOCK_BYTES", 8)
    path = _write(tmp_path / "a.csv", "# " + "x" * 100 + "\n\n  \n# more\nforce [kN]\n1\n2\n")
    rec, source = _same_as_read(path, [1, 2], rate=10.0)
    np.testing.assert_array_equal(rec.lanes["force"], [1000.0, 2000.0])
    _write(tmp_path / "e.csv", "\n  \n\t\n")
    _refused(r"empty file$", tmp_path / "e.csv")


# ----------------------------------------------------------------- binary and TDMS errors mid-file

def test_npy_and_raw_non_finite_mid_file(tmp_path):
    values = RNG.normal(0.0, 1.0, (200_000, 2))
    values[150_001, 1] = np.nan
    np.save(tmp_path / "a.npy", values)
    values.astype("<f4").tofile(tmp_path / "a.f32")
    for name, kwargs in (("a.npy", {}), ("a.f32", {"lanes": 2})):
        source = open_recording(tmp_path / name, rate=1000.0, **kwargs)
        seen = 0
        with pytest.raises(ValueError, match=r"sample 150001 of lane 'lane1' is nan; force samples must be finite"):
            for chunk in source.chunks(1000):
                seen += chunk.shape[0]
        assert 100_000 <= seen <= 150_001  # the chunks before the bad block came out first
        lane0 = open_recording(tmp_path / name, rate=1000.0, column="lane0", **kwargs)  # the other lane is fine
        np.testing.assert_array_equal(_joined(lane0, 70_000)[:, 0],
                                      values[:, 0].astype(np.float32 if name.endswith("f32") else np.float64))


def test_file_cut_short_after_opening(tmp_path):
    path = tmp_path / "a.f32"
    np.arange(400_000, dtype="<f4").tofile(path)
    source = open_recording(path, rate=10.0)
    with open(path, "r+b") as handle:
        handle.truncate(4 * 100_000)
    with pytest.raises(ValueError, match=r"the file ends at byte 400000, before byte 524288 .*\(truncated, or "
                                         r"changed since it was opened\)"):
        list(source.chunks(1000))


def test_tdms_non_finite_mid_file(tmp_path):
    data = np.arange(300_000.0)
    data[200_000] = np.inf
    path = _tdms(tmp_path / "a.tdms", [("a", data, {"wf_increment": 1e-4})])
    source = open_recording(path)
    with pytest.raises(ValueError, match=r"sample 200000 of lane 'daq/a' is inf"):
        list(source.chunks(4096))


# ----------------------------------------------------------------- TDMS, read as nptdms reads it

def _nptdms_values(path, names):
    from nptdms import TdmsFile

    tdms = TdmsFile.read(path)
    channels = {f"{group.name}/{channel.name}": channel for group in tdms.groups() for channel in group.channels()}
    return np.column_stack([np.asarray(channels[name][:], dtype=np.float64) for name in names])


@pytest.mark.parametrize("name,kwargs", [
    ("big_endian.tdms", {}),                   # big-endian, two segments, the second of 6 raw-data chunks
    ("raw_timestamps.tdms", {}),
    ("Digital_Input.tdms", {"column": "07/09/2012 06:58:23 PM - Digital Input - All Data/Dev1_port3_line7 - line 0"}),
    ("Digital_Input.tdms", {"column": "07/09/2012 06:58:23 PM - Digital Input - Decimated Data_Level1/"
                                      "Dev1_port3_line7 - line 0"}),
])
def test_nptdms_examples_chunked_as_nptdms_reads_them(name, kwargs):
    path = _example(name)
    rec, source = _same_as_read(path, [1, 3, 500, 1 << 16], **kwargs)
    np.testing.assert_array_equal(_matrix(rec), _nptdms_values(path, rec.lane_names))


def test_nptdms_daqmx_example_with_scaling(tmp_path):
    # raw1.tdms: DAQmx raw data (int16 words) with linear scaling to Volts; its unit renamed to newtons
    # (the same length, so every offset stays) to read it as force: the scaled values, as nptdms scales them
    raw = _example("raw1.tdms").read_bytes()
    assert raw.count(b"\x05\x00\x00\x00Volts") >= 2
    path = tmp_path / "raw1_newtons.tdms"
    path.write_bytes(raw.replace(b"\x05\x00\x00\x00Volts", b"\x05\x00\x00\x00N    "))
    rec, source = _same_as_read(path, [1, 77, 2000])
    assert rec.samples == 2000 and len(rec.lane_names) >= 2
    np.testing.assert_array_equal(_matrix(rec), _nptdms_values(path, rec.lane_names))
    assert np.ptp(_matrix(rec)) > 0.0


def _tdms_segment(channels, chunks=1, interleaved=False, big=False) -> bytes:
    """One TDMS segment written byte by byte from the format: the lead-in ("TDSm", table of contents,
    version 4713, offsets of the next segment and of the raw data), the metadata (objects with their
    raw-data index: type, dimension 1, values per chunk) and the raw data, ``chunks`` chunks of every
    channel in turn, or rows of one value of every channel (``interleaved``)."""
    order = ">" if big else "<"
    codes = {"i2": 2, "i4": 3, "f4": 9, "f8": 10}

    def string(text):
        data = text.encode()
        return struct.pack(order + "L", len(data)) + data

    objects = [("/", None), ("/'daq'", None)] + [(f"/'daq'/'{name}'", values) for name, values in channels]
    meta = struct.pack(order + "L", len(objects))
    for name, values in objects:
        meta += string(name)
        if values is None:
            meta += struct.pack(order + "L", 0xFFFFFFFF)
        else:
            meta += struct.pack(order + "LLLQ", 20, codes[values.dtype.str[1:]], 1, values.size // chunks)
        meta += struct.pack(order + "L", 0)
    if interleaved:
        rows = np.empty(channels[0][1].size, dtype=[(name, values.dtype.newbyteorder(order))
                                                    for name, values in channels])
        for name, values in channels:
            rows[name] = values
        data = rows.tobytes()
    else:
        data = b"".join(values.reshape(chunks, -1)[k].astype(values.dtype.newbyteorder(order)).tobytes()
                        for k in range(chunks) for _, values in channels)
    toc = (1 << 1) | (1 << 2) | (1 << 3) | ((1 << 5) if interleaved else 0) | ((1 << 6) if big else 0)
    return b"TDSm" + struct.pack("<l", toc) + struct.pack(order + "lQQ", 4713, len(meta) + len(data), len(meta)) \
        + meta + data


def test_tdms_segments_contiguous_interleaved_chunked_big_endian_and_cut_short(tmp_path):
    x = np.arange(6000)
    segments = [
        _tdms_segment([("a", (x[:1200] * 0.5).astype("f8")), ("b", x[:1200].astype("i4"))], chunks=3),
        _tdms_segment([("a", (x[1200:3000] * 0.5).astype("f8")), ("b", x[1200:3000].astype("i4"))],
                      interleaved=True, big=True),
        _tdms_segment([("a", (x[3000:4000] * 0.5).astype("f8")), ("b", x[3000:4000].astype("i4"))], chunks=4,
                      big=True),
        _tdms_segment([("a", (x[4000:6000] * 0.5).astype("f8")), ("b", x[4000:6000].astype("i4"))],
                      interleaved=True),
    ]
    path = tmp_path / "hand.tdms"
    path.write_bytes(b"".join(segments))
    rec, source = _same_as_read(path, [1, 999, 1000, 4096], rate=1000.0)
    assert rec.lane_names == ("daq/a", "daq/b") and rec.samples == 6000
    np.testing.assert_array_equal(_matrix(rec), np.column_stack([x * 0.5, x]))
    np.testing.assert_array_equal(_matrix(rec), _nptdms_values(path, rec.lane_names))
    # a recording cut in its last (interleaved, 12-byte rows) segment: the whole rows are read, as nptdms does
    path.write_bytes(b"".join(segments)[:-12 * 700 - 5])
    rec, _ = _same_as_read(path, [1, 4096], rate=1000.0)
    assert rec.samples == 6000 - 701
    np.testing.assert_array_equal(_matrix(rec), _nptdms_values(path, rec.lane_names))


def test_tdms_mixed_sizes_interleaved(tmp_path):
    x = np.arange(-500, 500)
    path = tmp_path / "mixed.tdms"
    path.write_bytes(_tdms_segment([("s", x.astype("i2")), ("f", (x / 4).astype("f4")), ("d", (x / 8).astype("f8"))],
                                   interleaved=True, big=True))
    rec, _ = _same_as_read(path, [1, 3, 1000], rate=50.0)
    np.testing.assert_array_equal(_matrix(rec), np.column_stack([x, x / 4, x / 8]))
    one, _ = _same_as_read(path, [1, 64], rate=50.0, column="f")
    np.testing.assert_array_equal(one.lanes["daq/f"], x / 4)


def test_tdms_long_pieces_interleaved_and_in_chunks(tmp_path):
    # pieces longer than a read block (2^16 values): interleaved rows of three sizes, chunks of two lanes
    x = np.arange(300_000)
    path = tmp_path / "long.tdms"
    path.write_bytes(_tdms_segment([("s", (x % 30000).astype("i2")), ("f", (x / 4).astype("f4")),
                                    ("d", (x / 8).astype("f8"))], interleaved=True, big=True)
                     + _tdms_segment([("s", (x % 30000).astype("i2")), ("f", (x / 4).astype("f4")),
                                      ("d", (x / 8).astype("f8"))], chunks=3))
    rec, _ = _same_as_read(path, [1 << 16, 100_000, 1 << 20], rate=50.0)
    expected = np.column_stack([x % 30000, x / 4, x / 8])
    np.testing.assert_array_equal(_matrix(rec), np.concatenate([expected, expected]))
    np.testing.assert_array_equal(_matrix(rec), _nptdms_values(path, rec.lane_names))


def _runs(path) -> dict:
    """How the TDMS reader will read each lane: its runs of pieces at fixed offsets, or None (nptdms)."""
    from nptdms import TdmsFile

    from fruitimpact.signals.read.tdms import _plan

    with TdmsFile.open(path) as tdms:
        segments = tdms._reader._segments
        return {f"{g.name}/{c.name}": _plan(segments, c) for g in tdms.groups() for c in g.channels()}


def test_tdms_plain_data_is_read_at_its_offsets(tmp_path):
    # not through nptdms's slices (which read a whole raw-data chunk for every slice): a logger's segments
    # laid out alike are one run; a scaled or DAQmx channel is left to nptdms
    runs = _runs(_many_segments(tmp_path / "many.tdms", np.zeros((3, 5000))))
    assert all(lane is not None and len(lane) == 1 and lane[0].pieces == 20 for lane in runs.values()), runs
    for name in ("big_endian.tdms", "raw_timestamps.tdms", "Digital_Input.tdms"):
        assert all(lane is not None for lane in _runs(_example(name)).values())
    assert all(lane is None for lane in _runs(_example("raw1.tdms")).values())


def _many_segments(path, x: np.ndarray):
    """Lanes ``x`` (lanes × samples, kN) written by nptdms as a logger does: 250 samples per segment."""
    from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

    properties = {"wf_increment": 1e-4, "unit_string": "kN"}
    with TdmsWriter(str(path)) as writer:
        for k in range(0, x.shape[1], 250):
            objects = [RootObject({}), GroupObject("daq")] if k == 0 else []
            writer.write_segment(objects + [ChannelObject("daq", f"c{j}", x[j, k:k + 250], properties=properties)
                                            for j in range(x.shape[0])])
    return path


def test_tdms_many_segments_written_by_nptdms(tmp_path):
    x = RNG.normal(0.0, 1.0, (3, 5000))
    rec, _ = _same_as_read(_many_segments(tmp_path / "many.tdms", x), [1, 249, 251, 4096])
    np.testing.assert_array_equal(_matrix(rec), x.T * 1e3)


def test_open_refuses_what_the_header_says(tmp_path):
    # every check that needs no sample is made by open_recording, before any chunk is asked for
    csv_path = _write(tmp_path / "a.csv", "time [s],f [V]\n" + "0,1\n" * 10)
    with pytest.raises(ValueError, match=r"force unit 'V' is not allowed"):
        open_recording(csv_path)
    with pytest.raises(ValueError, match=r"unknown column 'x' \(available: 'daq/a'\)"):
        open_recording(_tdms(tmp_path / "a.tdms", [("a", np.arange(3.0), {})]), column="x", rate=1.0)
    with pytest.raises(ValueError, match=r"rate is required: raw float32 files hold no time"):
        open_recording(write_recording(_recording(), tmp_path / "a.f32"))
    with pytest.raises(ValueError, match=r"rate=30000 Hz disagrees with the time column"):
        open_recording(write_recording(_recording(), tmp_path / "b.csv"), rate=30000.0)
    with pytest.raises(ValueError, match=r"lanes must be an integer >= 1"):
        open_recording(tmp_path / "missing.f32", lanes=0)


# ----------------------------------------------------------------- memory bounded by the chunk

def _peak(function) -> int:
    """Peak of the memory traced by tracemalloc [bytes] while ``function`` runs (numpy's buffers included)."""
    tracemalloc.start()
    try:
        function()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _write_long(path, suffix, samples):
    values = np.column_stack([np.sin(np.arange(samples) * 1e-3), np.arange(samples) % 1000 - 500.0])
    if suffix == "f32":
        values.astype("<f4").tofile(path)
    elif suffix == "npy":
        np.save(path, values)
    elif suffix == "tdms":
        _tdms(path, [("a", values[:, 0], {"wf_increment": 1e-4}), ("b", values[:, 1], {"wf_increment": 1e-4})])
    else:
        with open(path, "w") as handle:
            handle.write("time [ms],a,b\n")
            for start in range(0, samples, 100_000):
                t = np.arange(start, min(samples, start + 100_000))
                handle.write("".join(f"{i / 10},{i % 7},{i % 1000 - 500}\n" for i in t))


@pytest.mark.parametrize("suffix,samples", [("f32", 1 << 19), ("npy", 1 << 19), ("tdms", 1 << 19), ("csv", 1 << 16)])
def test_memory_is_bounded_by_the_chunk_not_the_file(tmp_path, monkeypatch, suffix, samples):
    # two files, one 4x the other; a one-segment TDMS file (its channels of 2^21 values each)
    monkeypatch.setattr(csvtable, "BLOCK_BYTES", 1 << 16)
    kwargs = {"rate": 10000.0, "lanes": 2} if suffix == "f32" else {"rate": 10000.0} if suffix == "npy" else {}
    peaks, full = [], None
    for n in (samples, 4 * samples):
        path = tmp_path / f"long{n}.{suffix}"
        _write_long(path, suffix, n)
        source = open_recording(path, **kwargs)
        peaks.append(_peak(lambda: sum(chunk.shape[0] for chunk in source.chunks(4096))))  # noqa: B023
        assert sum(chunk.shape[0] for chunk in source.chunks(4096)) == n
        full = _peak(lambda: read_recording(path, **kwargs))  # noqa: B023
    whole = 4 * samples * 2 * 8  # the float64 samples of the long file [bytes]
    assert full > whole, (full, whole)  # the instrument sees a file-sized reading
    assert peaks[1] < 1.2 * peaks[0] + (64 << 10), peaks  # 4x the file, (almost) the same peak
    assert peaks[1] < whole / 4, (peaks, whole)


def test_a_tdms_file_cut_short_is_read_with_one_warning(tmp_path):
    """A TDMS file cut mid-segment (a logger stopped, a copy interrupted): its complete samples are read, and the
    CLI says so in one warning line of its own, not nptdms's two multi-line log records; the library puts the
    same line in the frame's ``attrs["warnings"]``."""
    import subprocess
    import sys

    import fruitimpact as fi

    rec = _recording(lanes=1)
    whole = write_recording(rec, tmp_path / "whole.tdms")
    cut = tmp_path / "cut.tdms"
    cut.write_bytes(whole.read_bytes()[: whole.stat().st_size * 2 // 3])
    done = subprocess.run([sys.executable, "-m", "fruitimpact", "analyze", str(cut), "--json"], capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("fruitimpact analyze: warning:") and "cut short" in lines[0]
    frame = fi.analyze(cut)
    assert frame.attrs["warnings"] == [lines[0].split(f"{cut.name}: ", 1)[1]]
    assert fi.analyze(whole).attrs["warnings"] == []


@pytest.mark.parametrize("make, words", [
    (lambda p: np.save(p, np.r_[0.0, np.nan, 1.0]), "sample 1 of lane 'lane0' is nan"),
    (lambda p: np.save(p, np.zeros((3, 1000))), "1000 lanes (an array of 3 samples × 1000 lanes), at most 256"),
])
def test_a_bad_npy_recording_is_refused_before_any_work(tmp_path, script, make, words):
    """A NaN in the first samples of a .npy (or raw float32) recording was met while streaming: the table's header
    was printed, numba loaded, and the refusal came at 0.8 s; a 3 × 1000 array (lanes for samples) was refused as
    "lanes must be an integer in [1, 256]; got 1000", naming no argument (an attack).  Both are read when the
    file is opened, as a CSV's first rows are: one line, exit 2, nothing on stdout."""
    path = tmp_path / "rec.npy"
    make(path)
    done = script("analyze", str(path), "--rate", "20000", cwd=tmp_path)
    assert done.returncode == 2 and done.stdout == "" and words in done.stderr and len(done.stderr.splitlines()) == 1


def test_a_rate_too_low_for_the_detector_names_the_rate(tmp_path, script):
    """At 100 Hz the detector's 0.5 ms windows have no sample: the refusal named "offset_hold", a setting no
    option of the command sets (an attack); it is the rate's."""
    done = script("stream", "--rate", "100", cwd=tmp_path, input="")
    assert done.returncode == 2 and "argument --rate: the sample rate is too low for the detector" in done.stderr


def test_a_missing_sample_is_reported_where_it_is(tmp_path):
    """A CSV recording with one sample missing at row 50,001: its step is twice the others, and it pulled the mean
    interval off by 1e-5, so every interval failed the uniformity check and row 2 was named (an attack).  The
    gross step is looked for first and named at its own row (50,001 of the file: line 50,002)."""
    n = 100_000
    t = np.arange(n) / 20_000.0
    keep = np.ones(n, dtype=bool)
    keep[50_000] = False
    path = tmp_path / "gap.csv"
    np.savetxt(path, np.c_[t[keep], np.zeros(n)[keep]], fmt="%.6f", delimiter=",", header="time [s],force [N]",
               comments="")
    with pytest.raises(ValueError, match=r"non-uniform sampling at row 50001 \(line 50002\): interval 0\.0001 s"):
        for _ in read_recording(path).blocks():
            pass
