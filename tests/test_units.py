"""Unit parsing at the boundary: ``fruitimpact.impact.units.parse_quantity``.

The expected SI values below are written out by hand (not read from
``units.UNITS``) so that a wrong factor in the table is caught; a second test
walks ``UNITS`` itself so that every unit the parser claims to know parses.
"""

from __future__ import annotations

import math

import pytest

from fruitimpact.impact.units import SI_UNIT, UNITS, parse_quantity

# (text, dimension, SI value) -- one row per unit the CLI documents, factors by hand.
KNOWN = [
    # mass [kg]
    ("2kg", "mass", 2.0),
    ("115g", "mass", 0.115),
    ("250mg", "mass", 250e-6),
    # length [m]
    ("1.5m", "length", 1.5),
    ("30cm", "length", 0.30),
    ("65mm", "length", 0.065),
    ("40um", "length", 40e-6),
    ("40µm", "length", 40e-6),
    ("2in", "length", 0.0508),
    # modulus [Pa]
    ("7Pa", "modulus", 7.0),
    ("250kPa", "modulus", 250e3),
    ("3MPa", "modulus", 3e6),
    ("2GPa", "modulus", 2e9),
    ("5N/m2", "modulus", 5.0),
    ("5N/m^2", "modulus", 5.0),
    ("3N/mm2", "modulus", 3e6),
    ("3N/mm^2", "modulus", 3e6),
    # bruise susceptibility [m³/J]: 1 cm³ = 1 ml = 1e-6 m³, 1 mm³ = 1e-9 m³
    ("2e-6m3/J", "susceptibility", 2e-6),
    ("2e-6m^3/J", "susceptibility", 2e-6),
    ("4.66cm3/J", "susceptibility", 4.66e-6),
    ("4.66cm^3/J", "susceptibility", 4.66e-6),
    ("3ml/J", "susceptibility", 3e-6),
    ("500mm3/J", "susceptibility", 5e-7),
    ("500mm^3/J", "susceptibility", 5e-7),
    # volume [m³]
    ("1e-6m3", "volume", 1e-6),
    ("1e-6m^3", "volume", 1e-6),
    ("2cm3", "volume", 2e-6),
    ("2cm^3", "volume", 2e-6),
    ("2ml", "volume", 2e-6),
    ("500mm3", "volume", 5e-7),
    ("500mm^3", "volume", 5e-7),
    # velocity [m/s]
    ("1m/s", "velocity", 1.0),
    ("150cm/s", "velocity", 1.5),
    ("500mm/s", "velocity", 0.5),
    ("36km/h", "velocity", 10.0),
    # time [s]
    ("2s", "time", 2.0),
    ("10ms", "time", 0.01),
    ("100us", "time", 1e-4),
    ("100µs", "time", 1e-4),
    # stiffness [N/m^1.5]
    ("8e5N/m^1.5", "stiffness", 8e5),
    ("8e5N/m1.5", "stiffness", 8e5),
    ("800kN/m^1.5", "stiffness", 8e5),
    ("0.8MN/m^1.5", "stiffness", 8e5),
    # alpha [s/m]
    ("0.3s/m", "alpha", 0.3),
    # damping [N·s/m^2.5]
    ("9e5Ns/m^2.5", "damping", 9e5),
    ("9e5N*s/m^2.5", "damping", 9e5),
    ("9e5N.s/m^2.5", "damping", 9e5),
    # force [N]
    ("66N", "force", 66.0),
    ("1.5kN", "force", 1500.0),
    ("20mN", "force", 0.02),
    # firmness C [N/s] and C* [N/s²] (eqs 1, 2)
    ("37N/ms", "firmness", 37000.0),
    ("3.7e4N/s", "firmness", 37000.0),
    ("20N/ms^2", "firmness_star", 2.0e7),
    ("20N/ms2", "firmness_star", 2.0e7),
    ("20N/ms²", "firmness_star", 2.0e7),
    ("2e7N/s^2", "firmness_star", 2.0e7),
    ("2e7N/s2", "firmness_star", 2.0e7),
    ("2e7N/s²", "firmness_star", 2.0e7),
    # energy [J]
    ("2J", "energy", 2.0),
    ("38mJ", "energy", 0.038),
    # frequency [Hz]
    ("50Hz", "frequency", 50.0),
    ("2kHz", "frequency", 2000.0),
    # dimensionless
    ("0.37", "dimensionless", 0.37),
    ("37%", "dimensionless", 0.37),
]


@pytest.mark.parametrize("text, dimension, expected", KNOWN)
def test_each_unit(text, dimension, expected):
    assert parse_quantity(text, dimension) == pytest.approx(expected, rel=1e-14)


def test_table_of_known_units_covers_every_unit():
    """Every unit of ``UNITS`` appears in the hand-written table above."""
    covered = {(dim, text.lstrip("0123456789.e+-")) for text, dim, _ in KNOWN}
    missing = [(dim, unit) for dim, units in UNITS.items() for unit in units
               if unit and (dim, unit) not in covered]
    assert not missing, f"units without a hand-checked test: {missing}"


@pytest.mark.parametrize("dimension, unit, factor",
                         [(d, u, f) for d, units in UNITS.items() for u, f in units.items()])
def test_every_registered_unit_parses_with_and_without_space(dimension, unit, factor):
    assert parse_quantity(f"2.5{unit}", dimension) == pytest.approx(2.5 * factor, rel=1e-14)
    assert parse_quantity(f"2.5 {unit}", dimension) == pytest.approx(2.5 * factor, rel=1e-14)
    assert parse_quantity(f"  2.5  {unit}  ", dimension) == pytest.approx(2.5 * factor, rel=1e-14)


@pytest.mark.parametrize("dimension", sorted(UNITS))
@pytest.mark.parametrize("text, expected", [("0.065", 0.065), ("3", 3.0), ("-2", -2.0), ("+4.5", 4.5),
                                            (".5", 0.5), ("5.", 5.0), (" 7 ", 7.0)])
def test_plain_number_is_si(dimension, text, expected):
    """A bare number is taken as SI in every dimension (range checks live elsewhere)."""
    assert parse_quantity(text, dimension) == expected


@pytest.mark.parametrize("value", [0.115, 3, 0, -1.5])
def test_numeric_input_is_returned_as_float(value):
    result = parse_quantity(value, "mass")
    assert isinstance(result, float) and result == float(value)


@pytest.mark.parametrize("text, dimension, expected", [
    ("3 MPa", "modulus", 3e6),
    ("3\tMPa", "modulus", 3e6),
    (" 115 g ", "mass", 0.115),
    ("1 m/s", "velocity", 1.0),
    ("1e-3", "mass", 1e-3),
    ("1E3g", "mass", 1.0),
    ("2.5e+2 mm", "length", 0.25),
    ("3e6Pa", "modulus", 3e6),
    ("3.0E-1 MPa", "modulus", 3e5),
    ("1e-4 s", "time", 1e-4),
    ("6.5e1mm", "length", 0.065),
])
def test_whitespace_and_scientific_notation(text, dimension, expected):
    assert parse_quantity(text, dimension) == pytest.approx(expected, rel=1e-14)


@pytest.mark.parametrize("text, check", [
    ("inf", lambda v: v == math.inf),
    ("-inf", lambda v: v == -math.inf),
    ("Infinity", lambda v: v == math.inf),
    ("nan", math.isnan),
    ("NaN", math.isnan),
])
def test_non_finite_words_parse(text, check):
    """inf/nan parse (so that the range check, not the parser, rejects them with its range)."""
    assert check(parse_quantity(text, "mass"))


@pytest.mark.parametrize("text, dimension", [
    ("abc", "mass"),
    ("", "mass"),
    ("   ", "length"),
    ("kg", "mass"),
    ("5furlongs", "length"),
    ("3MPa", "mass"),           # a unit of another dimension
    ("115g", "length"),
    ("65mm", "modulus"),
    ("1m/s", "time"),
    ("10ms", "velocity"),       # ms is milliseconds, not metres per second
    ("1%", "mass"),
    ("1km/s", "velocity"),
    ("1e", "mass"),
    ("1..2", "mass"),
    ("1,5", "mass"),
    ("0x10", "mass"),
    ("--1", "mass"),
    ("e5", "mass"),
    ("1 kg kg", "mass"),
    ("3mpa", "modulus"),        # units are case-sensitive (mPa would be milli)
    ("3 s/m", "dimensionless"),
])
def test_bad_strings_raise_value_error_naming_allowed_units(text, dimension):
    with pytest.raises(ValueError) as info:
        parse_quantity(text, dimension)
    message = str(info.value)
    assert "\n" not in message
    assert repr(text) in message
    assert "units allowed:" in message
    for unit in (u for u in UNITS[dimension] if u):
        assert unit in message
    assert f"a plain number is {SI_UNIT[dimension] or 'dimensionless'}" in message
