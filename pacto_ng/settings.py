"""Typed settings with declared units, meanings and ranges: the parts of a run's configuration.

Each part of the configuration (mesh, material, design, schedule, loads, Darcy, objective,
Newton, optimiser, and a case's own options) is a frozen dataclass deriving from
:class:`Settings`, defined next to the code that reads it.  Its fields are declared with
:func:`setting`: a default, a unit, a one-line meaning and what values are allowed (a range or
a set of choices).  Construction checks every field against its declaration (type, finite,
range, choices) and then the part's own cross-constraints (:meth:`Settings.check`), so a
value is validated once, where it is used, and a new setting cannot be added without its
check.  :class:`~pacto_ng.params.Parameters` puts the parts together under their flat names.
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, fields

from .errors import InputError


def setting(default, unit: str = "", help: str = "", *, range: str | None = None,  # noqa: A002
            choices: tuple | None = None):
    """A declared setting: ``range`` is an interval such as ``"(0, 1]"``, ``"[0, inf)"`` (the
    bounds of the allowed values, open or closed); ``choices`` the allowed values."""
    bounds = _parse_range(range) if range else None
    return field(default=default, metadata={"unit": unit, "help": help, "range": range,
                                            "bounds": bounds, "choices": choices})


def _parse_range(text: str):
    text = text.strip()
    lo_open, hi_open = text[0] == "(", text[-1] == ")"
    lo, hi = (float(v) for v in text[1:-1].split(","))
    return lo, hi, lo_open, hi_open


def _kind(value) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    return "str"


def check_value(name: str, value, default, meta) -> None:
    """Raise InputError unless ``value`` fits the declaration of setting ``name``."""
    kind = _kind(default)
    ok_type = {"bool": isinstance(value, bool),
               "int": isinstance(value, numbers.Integral) and not isinstance(value, bool),
               "float": isinstance(value, numbers.Real) and not isinstance(value, bool),
               "str": isinstance(value, str)}[kind]
    if not ok_type:
        raise InputError(f"{name}: expected {'a number' if kind == 'float' else 'an integer' if kind == 'int' else 'a ' + kind} "
                         f"(got {value!r})")
    if kind in ("int", "float") and not math.isfinite(value):
        raise InputError(f"{name}: must be finite (got {value})")
    choices = meta.get("choices")
    if choices is not None and value not in choices:
        shown = ", ".join(repr(c) if isinstance(c, str) else str(c) for c in choices)
        raise InputError(f"{name}: must be one of {shown} (got {value!r})")
    bounds = meta.get("bounds")
    if bounds is not None:
        lo, hi, lo_open, hi_open = bounds
        below = value <= lo if lo_open else value < lo
        above = value >= hi if hi_open else value > hi
        if below or above:
            raise InputError(f"{name}: must lie in {meta['range']} (got {value:g})")


@dataclass(frozen=True)
class Settings:
    """Base of every part of the configuration: declared fields, checked at construction."""

    def __post_init__(self):
        for f in fields(self):
            if "unit" in f.metadata:  # declared with setting()
                check_value(f.name, getattr(self, f.name), f.default, f.metadata)
        self.check()

    def check(self) -> None:
        """Cross-constraints between this part's fields (InputError if violated)."""

    @classmethod
    def declared(cls) -> list:
        """The declared fields (dataclass fields) of this part."""
        return [f for f in fields(cls) if "unit" in f.metadata]
