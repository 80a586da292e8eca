"""The random numbers of a closed-loop run, drawn block by block (both arms, both paths).

Trial i of every controller uses seed index ``idx[i]``: its sensor noise comes from the
generator ``(seed, idx[i])`` and its measurement dropouts from ``(seed, idx[i], 1)``, so
controllers are compared on the same numbers (common random numbers) and a block of seeds run
alone gives the numbers it gives inside a full run. Blocks of :data:`CHUNK` samples bound the
memory: a generator fills arrays in order, so the numbers do not depend on the block size.
Every controller of a run meets the same numbers: :class:`RunNoise` draws them once for all of
them when they fit in :data:`SHARED_BYTES`.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np
from numpy.typing import NDArray

from adaptive_dd.benchmark.types import CHUNK

__all__ = ["SHARED_BYTES", "NoiseBlocks", "RunNoise", "trial_rngs"]

SHARED_BYTES = 32 * 2**20
"""Largest noise of a run (every trial's normals and dropouts over every sample) that
:class:`RunNoise` draws once and hands to each of the run's controllers (a drawn arm's task,
one seed: 1.5 MB; a shipped scenario at ten seeds: up to 24 MB)."""


def trial_rngs(seed: int, indices: Sequence[int]) -> list[np.random.Generator]:
    """The sensor-noise generators ``(seed, i)`` of the trials of seed indices ``indices``."""
    return [np.random.default_rng([int(seed), int(i)]) for i in indices]


class NoiseBlocks:
    """Sensor noise and dropouts of a run's trials, block by block.

    Parameters
    ----------
    scenario : Scenario
        Its ``seed`` and ``dropout`` (probability that a sample's measurement is lost, 0: none).
    indices : sequence of int
        Seed index of each trial.
    width : int
        Standard normals per trial and sample: ``2 n`` for ``n`` joints (q then qd).
    """

    def __init__(self, scenario, indices: Sequence[int], width: int) -> None:
        self.rngs = trial_rngs(scenario.seed, indices)
        self.p = float(scenario.dropout)
        self.drop_rngs = (
            [np.random.default_rng([int(scenario.seed), int(i), 1]) for i in indices] if self.p > 0 else None
        )
        self.width = int(width)

    @property
    def n_trials(self) -> int:
        return len(self.rngs)

    def block(self, m: int) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The next ``m`` samples: ``noise (S, m, width)`` standard normal and ``drop (S, m)``
        lost measurements (``(S, 0)`` without dropouts)."""
        noise = np.ascontiguousarray(np.stack([g.standard_normal((m, self.width)) for g in self.rngs]))
        if self.drop_rngs is None:
            return noise, np.zeros((self.n_trials, 0), dtype=np.bool_)
        return noise, np.ascontiguousarray(np.stack([g.random(m) < self.p for g in self.drop_rngs]))

    def blocks(self, n_samples: int) -> Iterator[tuple[int, int, NDArray[np.float64], NDArray[np.bool_]]]:
        """``(k0, k1, noise, drop)`` of samples ``k0 .. k1 - 1``: blocks of :data:`CHUNK` samples
        up to ``n_samples``."""
        for k0 in range(0, n_samples, CHUNK):
            k1 = min(n_samples, k0 + CHUNK)
            yield (k0, k1, *self.block(k1 - k0))


class RunNoise:
    """The blocks of :class:`NoiseBlocks` of a run's trials (``scenario, indices, width`` as
    there) over ``n_samples``, for each of the run's controllers in turn: drawn once and the
    same arrays handed to every controller (the closed loops read them, never write) when they
    take at most :data:`SHARED_BYTES`, else drawn afresh for each controller (the same numbers;
    the memory of one block at a time)."""

    def __init__(self, scenario, indices: Sequence[int], width: int, n_samples: int) -> None:
        self.draws = (scenario, tuple(indices), int(width))
        self.n_samples = int(n_samples)
        size = 8 * len(self.draws[1]) * self.n_samples * (self.draws[2] + 1)
        self.kept: list | None = [] if size <= SHARED_BYTES else None

    @property
    def n_trials(self) -> int:
        """The number of trials (seeds) the blocks cover."""
        return len(self.draws[1])

    def blocks(
        self, n_samples: int | None = None
    ) -> Iterator[tuple[int, int, NDArray[np.float64], NDArray[np.bool_]]]:
        """``(k0, k1, noise, drop)`` of each block, as :meth:`NoiseBlocks.blocks` (``n_samples``, if
        given, must be the run's)."""
        if n_samples is not None and int(n_samples) != self.n_samples:
            raise ValueError(f"RunNoise holds {self.n_samples} samples, asked for {n_samples}")
        if self.kept is None:
            return NoiseBlocks(*self.draws).blocks(self.n_samples)
        if not self.kept:
            self.kept = list(NoiseBlocks(*self.draws).blocks(self.n_samples))
        return iter(self.kept)
