"""The library refuses the same bad inputs as the CLI, with the same words.

``fruitimpact.Fruit(...)`` and ``fruitimpact.simulate(...)`` raise ``ValueError``
whose message is exactly the CLI's stderr line after its
``fruitimpact simulate: error: argument --x: `` prefix.
"""

from __future__ import annotations

import math

import pytest

import fruitimpact
from fruitimpact.cli import main

FRUIT_FIELDS = ("mass", "diameter", "modulus", "poisson", "stiffness")

# (library keyword, CLI value, SI float the library gets)
CASES = []
for _name in ("mass", "diameter", "modulus", "stiffness", "velocity", "drop_height", "step"):
    for _text in ("0", "-1", "nan", "inf", "-inf"):
        CASES.append((_name, _text, float(_text)))
for _text in ("-1", "0.5", "-1.5", "0.7", "nan", "inf"):
    CASES.append(("poisson", _text, float(_text)))
for _text in ("0", "-0.1", "1.0001", "nan", "2"):
    CASES.append(("restitution", _text, float(_text)))
for _text in ("-0.1", "-1", "nan", "inf"):
    CASES.append(("alpha", _text, float(_text)))
CASES += [
    ("model", "foo", "foo"),
    ("calibration", "approx", "approx"),
    ("method", "euler", "euler"),
    ("mass", "1e400", math.inf),
]


def _library_error(name, value) -> str:
    with pytest.raises(ValueError) as info:
        if name in FRUIT_FIELDS:
            fruitimpact.Fruit(**{name: value})
        else:
            fruitimpact.simulate(**{name: value})
    return str(info.value)


def _cli_error(capsys, name, text) -> str:
    option = "--" + name.replace("_", "-")
    status = main(["simulate", f"{option}={text}"])
    out, err = capsys.readouterr()
    assert status == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    prefix = f"fruitimpact simulate: error: argument {option}: "
    assert lines[0].startswith(prefix), lines[0]
    return lines[0][len(prefix):]


@pytest.mark.parametrize("name, text, value", CASES, ids=[f"{n}={t}" for n, t, _ in CASES])
def test_library_message_equals_cli_message(capsys, name, text, value):
    message = _library_error(name, value)
    assert "\n" not in message
    assert message.startswith(name + " ")  # names the argument
    assert message == _cli_error(capsys, name, text)


@pytest.mark.parametrize("name, value, allowed", [
    ("mass", 0.0, "> 0 kg"),
    ("diameter", -0.065, "> 0 m"),
    ("modulus", math.nan, "> 0 Pa"),
    ("stiffness", math.inf, "> 0 N/m^1.5"),
    ("poisson", 0.5, "(-1, 0.5)"),
    ("poisson", -1.0, "(-1, 0.5)"),
])
def test_fruit_rejects_out_of_range(name, value, allowed):
    # a NaN is named as such ("modulus is NaN; it must be ..."), never taken for the default
    with pytest.raises(ValueError, match=rf"^{name} (must be|is NaN; it must be) ") as info:
        fruitimpact.Fruit(**{name: value})
    assert allowed in str(info.value)
    assert f"got {value!r}" in str(info.value)


@pytest.mark.parametrize("kwargs, allowed", [
    (dict(velocity=0.0), "velocity must be a finite number > 0 m/s"),
    (dict(drop_height=-0.3), "drop_height must be a finite number > 0 m"),
    (dict(step=math.nan), "step is NaN; it must be a finite number > 0 s"),
    (dict(restitution=1.0001), "restitution must be in (0, 1]"),
    (dict(restitution=0.0), "restitution must be in (0, 1]"),
    (dict(alpha=-0.5, velocity=2.0), "alpha must be a finite number >= 0 s/m"),
    (dict(alpha=0.1, model="tsuji"), "alpha is Hunt–Crossley's damping parameter of the power-law laws"),
    (dict(model="foo"), "model must be one of hertz, hunt-crossley, herbert-mcwhannell"),
    (dict(calibration="foo"), "calibration must be one of paper, exact"),
    (dict(method="foo"), "method must be one of accurate, rk4"),
])
def test_simulate_rejects_out_of_range(kwargs, allowed):
    with pytest.raises(ValueError) as info:
        fruitimpact.simulate(**kwargs)
    assert str(info.value).startswith(allowed), str(info.value)


@pytest.mark.parametrize("kwargs, first, second", [
    (dict(velocity=1.0, drop_height=0.3), "velocity", "drop_height"),
    (dict(restitution=0.5, alpha=0.1), "restitution", "alpha"),
])
def test_simulate_rejects_conflicts(capsys, kwargs, first, second):
    with pytest.raises(ValueError) as info:
        fruitimpact.simulate(**kwargs)
    message = str(info.value)
    assert message == f"give either {first} or {second}, not both"
    # the CLI says the same with the options as typed
    argv = ["simulate"]
    for key, value in kwargs.items():
        argv += ["--" + key.replace("_", "-"), str(value)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    cli = f"give either --{first.replace('_', '-')} or --{second.replace('_', '-')}, not both"
    assert err == f"fruitimpact simulate: error: {cli}\n"


@pytest.mark.parametrize("name", ["mass", "diameter", "modulus", "poisson", "stiffness"])
def test_fruit_rejects_non_numbers(name):
    with pytest.raises(ValueError, match=rf"^{name} must be a number \(units allowed: .*\); got 'abc'$"):
        fruitimpact.Fruit(**{name: "abc"})


@pytest.mark.parametrize("name", ["velocity", "drop_height", "restitution", "alpha", "damping", "step"])
def test_simulate_rejects_non_numbers(name):
    with pytest.raises(ValueError, match=rf"^{name} must be a number \(units allowed: .*\); got 'abc'$"):
        fruitimpact.simulate(**{name: "abc"})


def test_library_reads_units_like_the_cli():
    """Strings with units are read by the library as by the CLI (before: a numba TypingError for step='1e-4')."""
    a = fruitimpact.simulate(fruitimpact.Fruit(mass="115g", diameter="65mm", modulus="3MPa"), velocity="1 m/s",
                             method="rk4", step="1e-4")
    b = fruitimpact.simulate(method="rk4", step=1e-4)
    assert a.characteristics == b.characteristics


@pytest.mark.parametrize("call, message", [
    (lambda: fruitimpact.simulate(model=["chen"]), "model must be one of hertz, "),
    (lambda: fruitimpact.simulate("banana"), "fruit must be one of jonathan-apple, apple, "),
    (lambda: fruitimpact.simulate(fruit=3), "fruit must be a Fruit, a fruit of the library"),
    (lambda: fruitimpact.simulate(surface="granite"), "surface must be one of rigid, steel, "),
    (lambda: fruitimpact.simulate(surface=3), "surface must be a Surface, a surface of the library"),
    (lambda: fruitimpact.simulate(velocty=2.0), "unknown input 'velocty'"),
    (lambda: fruitimpact.simulate(velocity=[1.0, 2.0]), "velocity must be a number"),
    (lambda: fruitimpact.simulate(method=None), "method must be one of accurate, rk4; got None"),
])
def test_wrong_kinds_of_argument_are_value_errors(call, message):
    """Before: simulate(model=["chen"]) and simulate("apple") ended in tracebacks of other types."""
    with pytest.raises(ValueError) as info:
        call()
    assert str(info.value).startswith(message), str(info.value)


def test_valid_library_call_matches_cli_defaults():
    result = fruitimpact.simulate(fruitimpact.Fruit(mass=0.115, diameter=0.065, modulus=3e6, poisson=0.37),
                                  velocity=1.0, restitution=0.577)
    assert result.success
    assert result.characteristics.restitution == pytest.approx(0.577, abs=1e-8)
    assert fruitimpact.simulate().to_dict()["peak_force"] == result.characteristics.peak_force
