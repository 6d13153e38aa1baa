"""Validation primitives for the harness's YAML files (worlds, scenarios).

Each parser takes (value, where) and returns the checked value or raises ValidationError with
`where`, the field's path (e.g. `objects[2].radius`), in the message.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

Colour = tuple[int, int, int]
Parser = Callable[[Any, str], Any]


class ValidationError(ValueError):
    """A field of a harness file is missing or malformed; the message names it."""


MISSING = object()


def join_path(path: str, key: str | int) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


def describe(value: Any) -> str:
    if value is None:
        return "null"
    kind = {bool: "bool", int: "int", float: "float", str: "str", list: "list", dict: "mapping"}
    return f"{kind.get(type(value), type(value).__name__)} {value!r}"


class Fields:
    """A mapping under validation: knows its path and rejects unknown keys (typos)."""

    def __init__(self, value: Any, path: str, allowed: set[str]):
        if not isinstance(value, dict):
            raise ValidationError(f"{path or 'world'}: must be a mapping, got {describe(value)}")
        unknown = sorted(str(k) for k in value if k not in allowed)
        if unknown:
            allowed_list = ", ".join(sorted(allowed))
            raise ValidationError(
                f"{join_path(path, unknown[0])}: unknown field (allowed: {allowed_list})"
            )
        self.data, self.path = value, path

    def has(self, key: str) -> bool:
        return key in self.data

    def where(self, key: str) -> str:
        return join_path(self.path, key)

    def get(self, key: str, parse: Parser, default: Any = MISSING) -> Any:
        if key not in self.data:
            if default is MISSING:
                raise ValidationError(f"{self.where(key)}: missing required field")
            return default
        return parse(self.data[key], self.where(key))

    def section(self, key: str, parse: Callable[[Any, str], Any]) -> Any:
        """Parse an optional sub-mapping; an absent one gets all its defaults."""
        return parse(self.data.get(key, {}), self.where(key))


def number(
    *,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
) -> Parser:
    def parse(value: Any, where: str) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ValidationError(f"{where}: must be a number, got {describe(value)}")
        v = float(value)
        if not math.isfinite(v):
            raise ValidationError(f"{where}: must be finite, got {value!r}")
        if gt is not None and not v > gt:
            raise ValidationError(f"{where}: must be > {gt:g}, got {value!r}")
        if ge is not None and not v >= ge:
            raise ValidationError(f"{where}: must be >= {ge:g}, got {value!r}")
        if lt is not None and not v < lt:
            raise ValidationError(f"{where}: must be < {lt:g}, got {value!r}")
        if le is not None and not v <= le:
            raise ValidationError(f"{where}: must be <= {le:g}, got {value!r}")
        return v

    return parse


def integer(*, ge: int | None = None) -> Parser:
    def parse(value: Any, where: str) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValidationError(f"{where}: must be an integer, got {describe(value)}")
        if ge is not None and value < ge:
            raise ValidationError(f"{where}: must be >= {ge}, got {value!r}")
        return value

    return parse


def boolean(value: Any, where: str) -> bool:
    if not isinstance(value, bool):
        raise ValidationError(f"{where}: must be true or false, got {describe(value)}")
    return value


def string(value: Any, where: str) -> str:
    if not isinstance(value, str) or not value:
        raise ValidationError(f"{where}: must be a non-empty string, got {describe(value)}")
    return value


def sequence(value: Any, where: str, *, min_len: int = 0) -> list:
    if not isinstance(value, list):
        raise ValidationError(f"{where}: must be a list, got {describe(value)}")
    if len(value) < min_len:
        raise ValidationError(f"{where}: needs at least {min_len} entries, got {len(value)}")
    return value


def vector(n: int, element: Parser | None = None) -> Parser:
    element = element or number()

    def parse(value: Any, where: str) -> tuple:
        items = sequence(value, where)
        if len(items) != n:
            raise ValidationError(f"{where}: must have {n} entries, got {len(items)}")
        return tuple(element(v, join_path(where, i)) for i, v in enumerate(items))

    return parse


def bgr_colour(value: Any, where: str) -> Colour:
    items = sequence(value, where)
    if len(items) != 3:
        raise ValidationError(f"{where}: must be a [b, g, r] colour, got {len(items)} entries")
    out = []
    for i, v in enumerate(items):
        if isinstance(v, bool) or not isinstance(v, int) or not 0 <= v <= 255:
            raise ValidationError(
                f"{join_path(where, i)}: must be an integer 0..255, got {describe(v)}"
            )
        out.append(v)
    return out[0], out[1], out[2]


def mapping(value: Any, where: str) -> dict:
    """Any mapping (keys are not checked), e.g. launch arguments or criteria."""
    if not isinstance(value, dict):
        raise ValidationError(f"{where}: must be a mapping, got {describe(value)}")
    return value
