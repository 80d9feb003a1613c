"""The design a run starts from: uniform at the volume fraction (or ``seed_density``), or the
final design of an earlier run on the same mesh (``init_design``)."""
from __future__ import annotations

import os
import zipfile
from pathlib import Path

import numpy as np

from .errors import InputError
from .problem import Problem


def initial_design(problem: Problem) -> np.ndarray:
    p = problem.params
    if p.init_design:
        return design_of_run(p.init_design, problem)
    x0 = p.seed_density if p.seed_density > 0 else p.volfrac
    x = np.full(problem.n_design, x0)
    if problem.n_design_fields == 2:
        x = np.concatenate([x, np.full(problem.n_design, 0.5)])
    return x


def design_of_run(folder: str | os.PathLike, problem: Problem) -> np.ndarray:
    """The design variables x of a run folder's checkpoint, for a run on the same mesh."""
    ckpt = Path(folder) / "checkpoint.npz"
    try:
        with np.load(ckpt, allow_pickle=False) as data:
            x = np.asarray(data["x"], dtype=float)
    except FileNotFoundError:
        raise InputError(f"init_design: no checkpoint.npz in '{folder}'") from None
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as err:
        raise InputError(f"init_design: cannot read '{ckpt}' ({err})") from None
    n = problem.n_design * problem.n_design_fields
    if x.shape != (n,):
        raise InputError(f"init_design: '{ckpt}' holds {x.size} design variables, this run has {n} "
                         "(another case or mesh)")
    if not np.all(np.isfinite(x)):
        raise InputError(f"init_design: '{ckpt}' holds non-finite design variables")
    return np.clip(x, 0.0, 1.0)
