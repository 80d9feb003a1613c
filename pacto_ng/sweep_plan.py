"""The plan of a sweep (``pacto sweep``): its grid of models and loads, each point's
parameters and folder name, and what is to be done with each folder (new, resumed, done).

Pure functions of their arguments and of the files in the sweep folder; no Dask.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

from .errors import InputError
from .params import Parameters
from .physics.materials import MODELS


@dataclass(frozen=True)
class SweepRun:
    """One grid point of a sweep.

    Attributes
    ----------
    model : str
        Mechanics model (``linear``, ``gnl``, ``neohookean`` or ``wang``).
    load : float
        Load magnitude in the case's unit.
    folder : str
        Name of the run folder inside the sweep folder (see :func:`folder_name`).
    """

    model: str
    load: float
    folder: str


# -- input ---------------------------------------------------------------------------------
def parse_loads(text: str | None) -> tuple[float, ...]:
    """Loads from a comma-separated list such as ``"1e5,1e6,1e7"``.

    Parameters
    ----------
    text : str or None
        The ``--loads`` argument.

    Returns
    -------
    tuple of float
        The loads in the given order.

    Raises
    ------
    InputError
        If the list is empty, an item is not a number, a load is not positive and finite, or two
        loads share a folder name.
    """
    items = [s.strip() for s in (text or "").split(",")]
    if not any(items):
        raise InputError("--loads: give at least one load, e.g. --loads 1e5,1e6,1e7")
    loads, labels = [], {}
    for item in items:
        try:
            val = float(item)
        except ValueError:
            raise InputError(f"--loads: '{item}' is not a number") from None
        if not (math.isfinite(val) and val > 0):
            raise InputError(f"--loads: loads must be positive and finite (got '{item}')")
        label = load_label(val)
        if label in labels:
            raise InputError(f"--loads: '{item}' repeats '{labels[label]}' (both are {label})")
        labels[label] = item
        loads.append(val)
    return tuple(loads)


def parse_models(text: str | None, default: str) -> tuple[str, ...]:
    """Models from a comma-separated list such as ``"linear,neohookean"``.

    Parameters
    ----------
    text : str or None
        The ``--models`` argument; None means ``default`` alone.
    default : str
        The case's model (after ``--set model=...``).

    Returns
    -------
    tuple of str
        The models in the given order.

    Raises
    ------
    InputError
        If the list is empty, names an unknown model or repeats one.
    """
    items = [default] if text is None else [s.strip() for s in text.split(",")]
    if not any(items):
        raise InputError(f"--models: give at least one model ({', '.join(MODELS)})")
    for i, m in enumerate(items):
        if m not in MODELS:
            raise InputError(f"--models: unknown model '{m}' (choose from {', '.join(MODELS)})")
        if m in items[:i]:
            raise InputError(f"--models: '{m}' appears twice")
    return tuple(items)


def load_label(load: float) -> str:
    """Short, stable text of a load for folder names: ``1e5``, ``2.5e5``, ``1e0``, ``5e-1``.

    Six significant digits, mantissa without trailing zeros, exponent without sign padding.
    """
    mant, exp = f"{load:.5e}".split("e")
    mant = mant.rstrip("0").rstrip(".")
    return f"{mant}e{int(exp)}"


def folder_name(model: str, load: float) -> str:
    """Name of the run folder of one grid point, e.g. ``linear-1e5``."""
    return f"{model}-{load_label(load)}"


def sweep_grid(models, loads) -> list[SweepRun]:
    """Every (model, load) pair, models outer, loads in the given order."""
    return [SweepRun(m, float(f), folder_name(m, f)) for m in models for f in loads]


def run_parameters(base: Parameters, run: SweepRun, case=None) -> Parameters:
    """The parameters of one grid point: ``base`` with the run's model and load (and, given the
    case, ``order`` = 0 resolved to the case's order for that model, as ``pacto run`` does)."""
    p = base.with_overrides({"model": run.model, "load": repr(run.load)})
    return case.resolve(p) if case is not None else p


# -- state of the folders ------------------------------------------------------------------
def read_json(path: Path) -> dict | None:
    """The JSON object in ``path``; None where it is missing, unreadable or not an object."""
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _as_json(params: Parameters) -> dict:
    return json.loads(json.dumps(params.to_dict()))


def run_status(folder: str | os.PathLike) -> str:
    """What a sweep has to do with a run folder.

    Returns
    -------
    str
        ``"done"`` if it holds a readable ``summary.json`` with an objective, ``"resume"`` if it
        holds a checkpoint (but no finished summary), ``"new"`` otherwise.
    """
    path = Path(folder)
    summ = read_json(path / "summary.json")
    if summ is not None and "objective" in summ:
        return "done"
    if (path / "checkpoint.npz").is_file():
        return "resume"
    return "new"


def check_same_parameters(folder: str | os.PathLike, params: Parameters, status: str) -> None:
    """Refuse to reuse a finished run or a checkpoint made with other parameters.

    Raises
    ------
    InputError
        Naming the first parameter that differs, if the stored parameters are not ``params``.
    """
    path = Path(folder)
    if status == "done":
        record = read_json(path / "summary.json") or {}
        stored = record.get("parameters")
    elif status == "resume":
        record = read_json(path / "params.json") or {}
        stored = record.get("params")
    else:
        return
    stored = dict(stored) if isinstance(stored, dict) else {}
    # the run stores what ``--model auto`` and ``load_ramp=-1`` resolved to; compare what it
    # was asked for
    for name, choice in (("model", "model_choice"), ("load_ramp", "load_ramp_choice")):
        if isinstance(record.get(choice), dict) and "requested" in record[choice]:
            stored[name] = record[choice]["requested"]
    want = _as_json(params)
    if stored == want:
        return
    diff = next((k for k in want if stored.get(k) != want[k]), "parameters")
    raise InputError(f"sweep: '{path}' holds a run with {diff} = {stored.get(diff)!r}, this sweep "
                     f"has {diff} = {want.get(diff)!r}: use another --out or remove that folder")
