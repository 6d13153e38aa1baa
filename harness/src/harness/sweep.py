"""Randomised sweeps: draw N runs from distributions over the fields a matrix can vary.

Member i draws from an RNG of its own, seeded by `member_seed(sweep seed, i)`: its values depend
on nothing else (not N, not the other members), so a member replays alone by its name
(`<family>/<index>_seed<seed>`). Parsing validates every distribution; errors name the field.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from harness.validation import (
    Fields,
    ValidationError,
    integer,
    mapping,
    number,
    sequence,
    vector,
)

KINDS = ("uniform", "normal", "choice")


@dataclass(frozen=True)
class Distribution:
    """One field's distribution: uniform over [low, high), normal (mean, sigma) optionally
    clipped to [low, high], or a choice among values (equally likely, or by `weights`)."""

    kind: str
    params: tuple
    clip: tuple[float, float] | None = None
    weights: tuple[float, ...] | None = None

    def draw(self, rng: np.random.Generator) -> Any:
        if self.kind == "uniform":
            return float(rng.uniform(*self.params))
        if self.kind == "normal":
            value = float(rng.normal(*self.params))
            return value if self.clip is None else float(np.clip(value, *self.clip))
        index = int(rng.choice(len(self.params), p=self.weights))
        return self.params[index]


def parse_distribution(value: Any, where: str) -> Distribution:
    """`{uniform: [low, high]}`, `{normal: [mean, sigma], clip: [low, high]}` (clip optional) or
    `{choice: [a, b, …], weights: [wa, wb, …]}` (weights optional, normalised)."""
    kinds = [k for k in KINDS if isinstance(value, dict) and k in value]
    if len(kinds) != 1:
        raise ValidationError(f"{where}: give exactly one of {', '.join(KINDS)}, got {value!r}")
    kind = kinds[0]
    f = Fields(value, where, {kind, {"normal": "clip", "choice": "weights"}.get(kind, kind)})
    if kind == "uniform":
        low, high = f.get(kind, vector(2, number()))
        if not high > low:
            raise ValidationError(f"{f.where(kind)}: needs low < high, got {value[kind]!r}")
        return Distribution(kind, (low, high))
    if kind == "normal":
        mean, sigma = f.get(kind, vector(2, number()))
        if sigma < 0:
            raise ValidationError(f"{f.where(kind)}: sigma must be >= 0, got {sigma:g}")
        clip = f.get("clip", vector(2, number()), None)
        if clip is not None and not clip[1] > clip[0]:
            raise ValidationError(f"{f.where('clip')}: needs low < high, got {value['clip']!r}")
        return Distribution(kind, (mean, sigma), clip=clip)
    options = tuple(sequence(f.get(kind, lambda v, w: v), f.where(kind), min_len=1))
    weights = f.get("weights", vector(len(options), number(ge=0.0)), None)
    if weights is not None:
        if sum(weights) <= 0:
            raise ValidationError(f"{f.where('weights')}: must not all be 0")
        weights = tuple(w / sum(weights) for w in weights)
    return Distribution(kind, options, weights=weights)


@dataclass(frozen=True)
class Sweep:
    seed: int
    runs: int
    vary: dict[str, Distribution]  # field path -> distribution, drawn in file order


def parse_sweep(value: Any, where: str = "sweep") -> Sweep:
    f = Fields(value, where, {"seed", "runs", "vary"})
    vary = f.get("vary", mapping)
    if not vary:
        raise ValidationError(f"{f.where('vary')}: must name at least one field")
    return Sweep(
        seed=f.get("seed", integer(ge=0)),
        runs=f.get("runs", integer(ge=1)),
        vary={
            str(path): parse_distribution(d, f"{f.where('vary')}.{path}")
            for path, d in vary.items()
        },
    )


def member_seed(sweep_seed: int, index: int) -> int:
    """Member `index`'s own seed (32 bits), from the sweep's seed and the index alone."""
    return int(np.random.SeedSequence([sweep_seed, index]).generate_state(1)[0])


def member_name(family: str, index: int, seed: int) -> str:
    return f"{family}/{index:03d}_seed{seed}"


def draw(sweep: Sweep, index: int) -> tuple[int, dict[str, Any]]:
    """Member `index`'s seed and its value for each varied field."""
    seed = member_seed(sweep.seed, index)
    rng = np.random.default_rng(seed)
    return seed, {path: d.draw(rng) for path, d in sweep.vary.items()}
