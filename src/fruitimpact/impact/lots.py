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
