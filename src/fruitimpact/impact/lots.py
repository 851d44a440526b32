"""A lot of fruit: members drawn reproducibly from the distributions of their inputs.

A member's inputs depend only on the seed and its row number: input ``name`` of the rows in block ``b``
(rows ``b*BLOCK_ROWS`` onwards) is drawn, a whole block at a time, from the generator of
``SeedSequence(seed, spawn_key=(b, stream_number(name)))``.  So the same lot comes out whatever the chunk
size, the engine (in process or Dask), an interruption, or whether a line audit or a population run draws it.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

from fruitimpact.impact.labels import Labels
from fruitimpact.impact.quantities import INPUTS

#: Largest seed of a lot: numpy's SeedSequence takes any integer, but 128 bits is all the entropy it keeps in
#: its pool, and a bound answers "1e9999999" at once instead of building a ten-million-digit integer.
MAX_SEED = 2 ** 128 - 1
#: Rows per random block of a lot (a member's draws depend on its row, not on how the rows are cut).
BLOCK_ROWS = 65_536

#: Random streams of the population inputs, by input: the first ten are the order of earlier
#: versions (so their populations are unchanged); inputs added later get a stream from their name.
_LEGACY_STREAMS = ("mass", "diameter", "modulus", "poisson", "stiffness", "velocity", "drop_height", "restitution",
                   "alpha", "step")
#: Random stream of the percentile-sample keys.
KEY_STREAM = 1000
#: The largest lot or grid validated whole before a run (``read_lot``, ``runs.tasks.sweep_plan``): a few ms.
PRECHECK_ROWS = 4096


def stream_number(name: str) -> int:
    """The random stream of population input ``name``: fixed for the first ten inputs, derived
    from the name (CRC-32, above the key stream) for the others, so adding an input to the
    table of quantities changes no one's draws."""
    if name in _LEGACY_STREAMS:
        return _LEGACY_STREAMS.index(name)
    return KEY_STREAM + 1 + zlib.crc32(name.encode())


def _generator(seed: int, block: int, stream: int) -> np.random.Generator:
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(block, stream))))


@dataclass(frozen=True)
class PopulationSource:
    """``rows`` members; numeric inputs drawn from distributions, text inputs fixed.

    Input ``name`` of the rows in block ``b`` (rows ``b*BLOCK_ROWS`` onwards) is
    drawn, a whole block at a time, from the generator of
    ``SeedSequence(seed, spawn_key=(b, stream_number(name)))``; so each input has
    its own stream and a member's inputs depend only on ``seed`` and its row number."""

    distributions: tuple  # of (name, distribution)
    text: tuple  # of (name, value)
    rows: int
    seed: int
    #: Density [kg/m³] from which each member's diameter follows its drawn mass, d = (6 m / (π ρ))^(1/3)
    #: (a lot drawn from a fruit's spreads: a heavier fruit is a bigger one); None: no such column.
    diameter_density: float | None = None

    def identity(self) -> dict:
        identity = {"population": {name: dist.identity() for name, dist in self.distributions},
                    "text": dict(self.text), "rows": self.rows, "seed": self.seed, "block": BLOCK_ROWS}
        if self.diameter_density is not None:
            identity["diameter_density"] = self.diameter_density
        return identity

    def payloads(self, chunk_rows: int):
        for index in range(-(-self.rows // chunk_rows)):
            yield index, None

    def _stream(self, start: int, stop: int, stream: int, draw) -> np.ndarray:
        if stop <= start:
            return np.empty(0)
        blocks = range(start // BLOCK_ROWS, (stop - 1) // BLOCK_ROWS + 1)
        values = np.concatenate([draw(_generator(self.seed, b, stream), BLOCK_ROWS) for b in blocks])
        offset = blocks[0] * BLOCK_ROWS
        return values[start - offset:stop - offset]

    def changed(self) -> bool:
        return False

    def inputs(self, start: int, stop: int, payload) -> tuple:
        """(columns, None): the members start..stop-1."""
        from fruitimpact.impact.distributions import Constant

        columns = {}
        for name, dist in self.distributions:
            if isinstance(dist, Constant):
                columns[name] = np.full(stop - start, dist.value)
            else:
                columns[name] = self._stream(start, stop, stream_number(name), dist.draw)
        if self.diameter_density is not None and "mass" in columns:
            columns["diameter"] = np.cbrt(6.0 * columns["mass"] / (np.pi * self.diameter_density))
        for name, value in self.text:
            columns[name] = Labels.constant(value, stop - start)
        # with every input at its default there would be no column to carry the row count
        columns.setdefault("model", Labels.constant(INPUTS["model"].default, stop - start))
        return columns, None

    def keys(self, start: int, stop: int) -> np.ndarray:
        """Uniform [0, 1) keys of rows start..stop-1, for the percentile sample."""
        return self._stream(start, stop, KEY_STREAM, lambda rng, n: rng.random(n))


def read_lot(inputs, *, rows: int, seed: int, spreads: bool = True, criterion: str | None = None,
             excluded=(), excluded_reason: str = "", fixed=()):
    """(source, text inputs, lines describing the library spreads) of a lot of ``rows`` fruit, from ``inputs``
    (input → a constant ``0.115``/``"115g"``, a distribution text ``"normal(115g,10g)"``, or a name for the text
    inputs), as ``population`` and a line audit both take them.

    Every input is checked before anything is drawn: an unknown name, an input of ``excluded`` (``excluded_reason``
    says why), a text input not in its registry, a distribution that cannot be read, two alternatives given
    together, a constant out of its range or one the others need (``impact.refusals.refuse_constants``).  The
    inputs not given are drawn from the fruit's library spreads unless ``spreads`` is False (the bruise inputs
    only with a ``criterion``), except those of ``fixed`` (each evaluation of the lot sets them: a risk map's
    axis).  ``InputError`` naming the input otherwise."""
    from fruitimpact.impact.distributions import Constant, parse_distribution
    from fruitimpact.impact.presets import lot_distributions
    from fruitimpact.impact.registries import REGISTRIES
    from fruitimpact.impact.validation import (InputError, check_choice, check_conflicts, check_input_name,
                                               refuse_out_of_range, spec_text)

    distributions, constants, text = [], {}, {}
    for name, value in inputs.items():
        quantity = check_input_name(name)
        if value is None:
            continue
        if name in excluded:
            raise InputError(f"{name} {excluded_reason}", name)
        spec = spec_text(name, value)
        if not quantity.numeric:
            text[name] = check_choice(name, spec, REGISTRIES[name]) if name in REGISTRIES else spec
            continue
        try:
            dist = parse_distribution(spec, quantity.dimension, name)
        except ValueError as exc:
            raise InputError(f"{name}: {exc}", name) from None
        distributions.append((name, dist))
        if isinstance(dist, Constant):
            constants[name] = dist.value
    criterion = criterion if criterion is not None else text.get("criterion")
    given = [name for name, _ in distributions] + list(text)
    check_conflicts(given)
    refuse_out_of_range(constants)  # at once: the one-row evaluation below loads the engine (numba)
    from fruitimpact.impact.refusals import refuse_constants

    refuse_constants(constants, {**text, **({"criterion": criterion} if criterion else {})}, given)
    extra, density, described, bases = lot_distributions(text.get("fruit"),
                                                         [name for name, _ in distributions] + list(fixed),
                                                         criterion, spreads=spreads)
    if bases:
        extra, described = _one_bruise_basis(extra, described, dict(bases), distributions, text)
    source = PopulationSource(tuple(distributions) + tuple(extra), tuple(text.items()), rows, seed, density)
    if not excluded and not fixed and rows <= PRECHECK_ROWS:
        # a lot small enough to validate whole before the run (a few ms): an input of the user's (a constant or a
        # distribution) that every member fails, such as a step too coarse for rk4 or a mass drawn below zero, is
        # a usage error; a larger lot is left to its rows (one runnable fruit among them must run), and a run with
        # no row ok says so in its exit status.  Not where each point or axis sets inputs later.
        from fruitimpact.impact.refusals import refuse_lot

        refuse_lot(source.inputs(0, rows, None)[0], given, f"the lot's {rows:,} fruit")
    return source, text, tuple(described)


def _one_bruise_basis(extra, described, bases: dict, distributions, text: dict):
    """The drawn library spreads and their description, with the rows' ``bruise_basis`` set in ``text``.

    A drawn bruise value is a given value to the evaluation, and a row's given bruise values share one basis (the
    text input ``bruise_basis``).  That basis is the user's (their ``--bruise-basis``, or its default for a bruise
    value they gave), else that of the drawn threshold energy (the energy criterion's onset), else the
    susceptibility's.  A library value measured on the other basis is not drawn: it stays the library value, which
    keeps its own basis, and the description says so (never a value applied on a basis it was not measured on)."""
    own = [name for name, _ in distributions if name in ("bruise_susceptibility", "bruise_energy")]
    if "bruise_basis" in text:
        basis, whose = text["bruise_basis"], "the given --bruise-basis"
    elif own:
        basis = INPUTS["bruise_basis"].default
        whose = f"the default --bruise-basis of the given {' and '.join(own)}"
    else:
        basis = bases.get("bruise_energy", bases.get("bruise_susceptibility"))
        whose = "the drawn " + ("bruise_energy" if "bruise_energy" in bases else "bruise_susceptibility")
    kept, lines = [], list(described)
    for name, dist in extra:
        if name in bases and bases[name] != basis:
            lines = [f"{name}: the library value, not drawn (measured on the {bases[name]} energy; the rows carry "
                     f"{whose}, {basis})" if line.startswith(f"{name}: ") else line for line in lines]
            continue
        kept.append((name, dist))
    if any(name in bases for name, _ in kept) or own or "bruise_basis" in text:
        text["bruise_basis"] = basis
    return tuple(kept), tuple(lines)


def lot_details(source: PopulationSource, described) -> dict:
    """What a lot was drawn from, for a report: the seed, each drawn input's distribution and the lines
    describing the library spreads."""
    return {"seed": source.seed, "inputs": {name: dist.describe() for name, dist in source.distributions},
            "spreads": list(described)}
