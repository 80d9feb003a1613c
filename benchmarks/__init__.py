"""Benchmarks: speed/accuracy studies that write docs/studies.md (not tests)."""


def perturbed(x):
    """``x`` moved by 1 % of the range (smooth in the element index), within [0, 1]: the other
    design of the timed evaluations, which alternate between the two as an optimisation's
    evaluations do (a warm-started solve then never finds the state already in equilibrium)."""
    import numpy as np

    return np.clip(x + 0.01 * np.sin(np.arange(len(x)) * 0.37), 0.0, 1.0)
