"""Seeded faults on the arm→host line: lost status frames, corrupted ones, noise bytes.

Strategy: each fault draws from its own ``random.Random`` seeded from ``(seed, fault name)``, so
a run is reproducible from its seed and changing one rate does not reshuffle the others.  Each
status frame is judged once, in order:
- preceded, with probability ``noise_rate``, by a burst of 1…``NOISE_BURST_MAX_BYTES`` random
  bytes (so ``noise_rate`` is the share of frame slots with noise in front of them);
- lost with probability ``loss_rate`` (nothing but that noise goes on the wire);
- otherwise corrupted with probability ``corrupt_rate``: one byte, chosen uniformly, is XORed
  with a random non-zero mask (the frame may still look valid — H9: readers must judge values).
Host→arm bytes are never disturbed: a lost command would make "no frame dropped" unprovable.
Pure: no clock, no I/O.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

NOISE_BURST_MAX_BYTES = 4


def _rate(name: str, value: float) -> float:
    if not 0.0 <= value <= 1.0:
        raise ValueError(f"{name} must be between 0 and 1, not {value!r}")
    return float(value)


@dataclass
class FaultCounts:
    frames_lost: int = 0
    frames_corrupted: int = 0
    noise_bytes: int = 0


class StatusFaults:
    """Turns each clean status frame into the bytes that actually go on the wire."""

    def __init__(self, loss_rate: float = 0.0, corrupt_rate: float = 0.0, noise_rate: float = 0.0, seed: int = 0):
        self.loss_rate = _rate("loss rate", loss_rate)
        self.corrupt_rate = _rate("corrupt rate", corrupt_rate)
        self.noise_rate = _rate("noise rate", noise_rate)
        self._loss = random.Random(f"{seed}/loss")
        self._corrupt = random.Random(f"{seed}/corrupt")
        self._noise = random.Random(f"{seed}/noise")
        self.counts = FaultCounts()

    @property
    def active(self) -> bool:
        return bool(self.loss_rate or self.corrupt_rate or self.noise_rate)

    def apply(self, frame: bytes) -> bytes:
        if not self.active:
            return frame
        out = b""
        if self.noise_rate and self._noise.random() < self.noise_rate:
            burst = bytes(self._noise.randrange(256) for _ in range(self._noise.randint(1, NOISE_BURST_MAX_BYTES)))
            self.counts.noise_bytes += len(burst)
            out = burst
        if self.loss_rate and self._loss.random() < self.loss_rate:
            self.counts.frames_lost += 1
            return out
        if self.corrupt_rate and self._corrupt.random() < self.corrupt_rate:
            damaged = bytearray(frame)
            damaged[self._corrupt.randrange(len(damaged))] ^= self._corrupt.randint(1, 255)
            self.counts.frames_corrupted += 1
            frame = bytes(damaged)
        return out + frame
