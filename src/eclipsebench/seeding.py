"""One source of randomness for the whole package.

Policy
------
A run has one integer seed. Every random stream is derived from it with
:class:`numpy.random.SeedSequence` and a *spawn key* built from the names of
what the stream is for, e.g. ``("simulate", epoch, "noise")`` or
``("reduce", epoch, method, "mcmc")``. The key is hashed stably (BLAKE2b, not
Python's salted ``hash``), so a stream depends only on the seed and on what it
is for, never on the order in which tasks run or on the number of workers.
The same seed therefore gives the same bytes with one worker or many, and two
different keys give independent streams.
"""

from __future__ import annotations

import hashlib

import numpy as np

__all__ = ["key_to_int", "seed_sequence", "rng", "spawn_ints"]


def key_to_int(part: object) -> int:
    """Map one spawn-key part (int or str) to a non-negative 32-bit integer.

    Integers are used as they are (they must be non-negative); strings and
    other objects are hashed with BLAKE2b of their ``str``.
    """
    if isinstance(part, (int, np.integer)) and not isinstance(part, bool):
        value = int(part)
        if value < 0:
            raise ValueError(f"spawn key parts must be non-negative, got {value}")
        return value
    digest = hashlib.blake2b(str(part).encode("utf-8"), digest_size=4).digest()
    return int.from_bytes(digest, "little")


def seed_sequence(seed: int, *key: object) -> np.random.SeedSequence:
    """The :class:`~numpy.random.SeedSequence` of ``seed`` for the task ``key``.

    Parameters
    ----------
    seed : int
        The run's seed (non-negative).
    *key : int or str
        What the stream is for, most general first, e.g.
        ``seed_sequence(7, "simulate", 3, "pointing")``.
    """
    if int(seed) < 0:
        raise ValueError(f"seed must be non-negative, got {seed}")
    return np.random.SeedSequence(int(seed), spawn_key=tuple(key_to_int(k) for k in key))


def rng(seed: int, *key: object) -> np.random.Generator:
    """A :class:`numpy.random.Generator` (PCG64) for ``seed`` and task ``key``."""
    return np.random.Generator(np.random.PCG64(seed_sequence(seed, *key)))


def spawn_ints(seed: int, *key: object, n: int = 1) -> list[int]:
    """``n`` independent 32-bit integer seeds for libraries that take an int."""
    return [int(v) for v in seed_sequence(seed, *key).generate_state(n, dtype=np.uint32)]
