"""Reading force recordings (issue 8, item 1): ``Recording`` and ``signals.read_recording``.

References: files written here by hand (CSV text, ``numpy.save``, raw bytes
from ``numpy.tofile``, ``nptdms.TdmsWriter``) with values chosen in the test,
and the example TDMS files that ship inside the nptdms wheel
(``nptdms/test/data``, written by LabVIEW / DAQmx), whose expected values are
those asserted by npTDMS's own tests (``nptdms/test/test_example_files.py``).
Round trips go through ``signals.synth.write_recording``; CSV floats are written
as shortest round-trip decimals, so they read back bit-identical; float32
files read back as the float32 rounding of the values, exactly.
"""

from __future__ import annotations

import importlib.resources
import math

import numpy as np
import pytest

from fruitimpact.signals import Recording, read_recording, write_recording

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
    ({"rate": -1.0}, r"rate must be a finite number > 0 Hz"),
    ({"rate": math.inf}, r"rate must be a finite number > 0 Hz"),
    ({"rate": True}, r"rate must be a number"),
    ({"rate": "20kHz"}, r"rate must be a number"),
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
