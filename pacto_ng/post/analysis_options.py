"""The options of ``pacto analyse``, for a run's part (:mod:`.analyse`) and for a case as
built (:mod:`.as_built`): the pressures of the sweep, the kinds of analysis, and the
analysis's parameters (model, displacement order).
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import InputError
from ..params import Parameters

#: a case's part as built: its displacement order when ``--order`` is not given, by dimension
#: (a run's part: the order and element size of the run's own part, :mod:`.part_stage`)
DEFAULT_ORDER = {2: 2, 3: 1}


def parse_pressures(text: str) -> list[float]:
    """``"1e5,1e6"`` -> ``[1e5, 1e6]`` (sorted, duplicates removed); InputError otherwise."""
    out = []
    for item in str(text).split(","):
        item = item.strip()
        try:
            val = float(item)
        except ValueError:
            raise InputError(f"--pressures: cannot read '{item}' as a pressure (expected "
                             f"comma-separated numbers, e.g. 1e5,1e6)") from None
        if not math.isfinite(val) or val <= 0:
            raise InputError(f"--pressures: pressures must be positive and finite (got {item})")
        out.append(val)
    return sorted(set(out))


def default_pressures(load: float, n: int = 5, span: float = 100.0) -> list[float]:
    """``n`` log-spaced pressures from ``load / span`` to ``load``."""
    return [float(v) for v in np.geomspace(load / span, load, n)]


def check_kinds(kinds, allowed) -> tuple:
    """``--kinds``: a non-empty selection of ``allowed`` (in its order)."""
    kinds = tuple(kinds)
    bad = [k for k in kinds if k not in allowed]
    if bad or not kinds:
        raise InputError(f"--kinds: choose from {', '.join(allowed)} (got "
                         f"{','.join(kinds) or 'none'})")
    return tuple(k for k in allowed if k in kinds)


def analysis_params(params: Parameters, model: str | None, order: int) -> Parameters:
    """The part analysis's parameters: ``params`` with ``model`` (if given) and ``order``."""
    if order not in (1, 2, 3):
        raise InputError(f"--order: must be 1, 2 or 3, got {order}")
    if model == "auto" or (model is None and params.model == "auto"):
        raise InputError("--model: auto is chosen by a run from its first analysis; name the "
                         "model of the part's analysis")
    return params.replace(order=order, **({"model": model} if model else {}))
