"""Block protocol, the explicit chain, and the gradient (finite-difference / Taylor) check.

Every step of the optimisation chain is a *block*: ``forward(*inputs) -> output`` and
``backward(grad_output) -> tuple(grad per input)``.  Values are numpy arrays (element-wise
fields), NGSolve ``BaseVector`` objects (finite-element states) or floats (responses).  A
gradient has the type of the value it belongs to.  A block returns ``None`` for an input it
does not depend on.

A :class:`Chain` is a list of blocks whose named inputs and outputs form a DAG, evaluated in
order.  ``Chain.gradient(name)`` runs the backward pass for one scalar output and accumulates
the gradient of every named value; the adjoint of a solve block is simply its backward pass.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable, Protocol, Sequence, runtime_checkable

import numpy as np


@runtime_checkable
class Block(Protocol):
    """One differentiable step.  ``inputs`` names what it consumes, ``output`` what it makes."""

    inputs: tuple[str, ...]
    output: str

    def forward(self, *values: Any) -> Any:  # pragma: no cover - protocol
        ...

    def backward(self, grad_output: Any) -> tuple[Any, ...]:  # pragma: no cover - protocol
        ...


def _accumulate(store: dict, name: str, grad: Any) -> None:
    if grad is None:
        return
    if name not in store:
        if isinstance(grad, np.ndarray):
            store[name] = grad.copy()
        elif isinstance(grad, float | int | np.floating):
            store[name] = float(grad)
        else:  # NGSolve vector
            v = grad.CreateVector()
            v.data = grad
            store[name] = v
    else:
        if isinstance(grad, np.ndarray) or isinstance(store[name], float):
            store[name] = store[name] + grad
        else:
            store[name].data += grad


class Chain:
    """An explicit, ordered composition of blocks (a small DAG by names).

    Parameters
    ----------
    blocks : sequence of Block
        In an order where every input of a block is either a chain input or the output of an
        earlier block.
    inputs : sequence of str
        The names supplied to :meth:`forward`.
    """

    def __init__(self, blocks: Sequence[Block], inputs: Sequence[str] = ("x",)):
        self.blocks = list(blocks)
        self.inputs = tuple(inputs)
        known = set(self.inputs)
        for b in self.blocks:
            missing = [n for n in b.inputs if n not in known]
            if missing:
                raise ValueError(f"block {type(b).__name__} needs {missing} before it is computed")
            if b.output in known:
                raise ValueError(f"value '{b.output}' is produced twice")
            known.add(b.output)
        self.values: dict[str, Any] = {}

    def forward(self, **inputs: Any) -> dict[str, Any]:
        """Evaluate every block; returns (and keeps) the dictionary of all values.

        An intermediate value may be given as an input (e.g. ``rho_bar=...`` to analyse a given
        physical density): the blocks that produce it, and those whose inputs are then missing,
        are skipped.
        """
        vals = dict(inputs)
        self.values = vals  # kept as it fills: after a failure the values before it are there
        for b in self.blocks:
            if b.output in vals or any(n not in vals for n in b.inputs):
                continue
            vals[b.output] = b.forward(*(vals[n] for n in b.inputs))
        self.values = vals
        return vals

    def gradient(self, output: str, wrt: str = "x") -> Any:
        """d(output)/d(wrt) by the backward pass (after :meth:`forward`)."""
        grads: dict[str, Any] = {output: 1.0}
        for b in reversed(self.blocks):
            if b.output not in grads:
                continue
            gin = b.backward(grads[b.output])
            if len(gin) != len(b.inputs):
                raise RuntimeError(f"{type(b).__name__}.backward returned {len(gin)} gradients "
                                   f"for {len(b.inputs)} inputs")
            for name, g in zip(b.inputs, gin):
                _accumulate(grads, name, g)
        if wrt not in grads:
            return np.zeros_like(np.asarray(self.values[wrt], dtype=float))
        return grads[wrt]


# ----------------------------------------------------------------------------------------
# Gradient checks
# ----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class GradientCheck:
    """Result of a central finite-difference check of a gradient along random directions."""

    analytic: np.ndarray  # directional derivatives from the adjoint
    numeric: np.ndarray  # central differences
    rel_error: float  # worst relative error over the directions
    step: float
    stencil: int = 2  # points of the central difference (2: O(h²), 4: O(h⁴))
    cancellation: float = 1.0  # largest Σ|g_i d_i| / |g·d| of the directions used

    def __str__(self) -> str:
        order = "" if self.stencil == 2 else f", {self.stencil + 1}-point stencil"
        return (f"worst relative error {self.rel_error:.2e} (h = {self.step:g}{order}, "
                f"cancellation ≤ {self.cancellation:.0f})")


def check_gradient(fun: Callable[[np.ndarray], float], grad: Callable[[np.ndarray], np.ndarray],
                   x0: np.ndarray, *, h: float = 1e-6, directions: int = 3,
                   lower: float | None = None, upper: float | None = None,
                   seed: int = 0, stencil: int = 2,
                   max_cancellation: float | None = None) -> GradientCheck:
    """Compare ``grad(x0)·d`` with a central difference of ``fun`` along random ``d``.

    ``stencil=2``: ``(f(x+hd) - f(x-hd)) / 2h`` (error O(h²)); ``stencil=4``: the five-point
    ``(f(x-2hd) - 8f(x-hd) + 8f(x+hd) - f(x+2hd)) / 12h`` (error O(h⁴)), which allows a larger
    step, so that the noise of the function values (e.g. an equilibrium solved to a residual
    tolerance) is divided by a larger h.

    The relative error of each direction is ``|a - n| / max(|a|, |n|, tiny)`` where ``tiny``
    is 1e-12 times the largest magnitude met, so that a vanishing derivative is not reported as
    a 100 % error.  ``lower``/``upper`` keep the points within bounds.

    ``max_cancellation``: a direction whose derivative ``g·d`` is smaller than ``Σ|g_i d_i|`` by
    more than this factor is drawn again (up to 50 times): along such a direction the response
    is nearly stationary, the relative error measures the finite difference's own error
    amplified by that factor, and not the gradient.  The factor of the directions used is in
    ``GradientCheck.cancellation``.
    """
    if stencil not in (2, 4):
        raise ValueError("stencil: must be 2 or 4")
    rng = np.random.default_rng(seed)
    x0 = np.asarray(x0, dtype=float)
    g = np.asarray(grad(x0), dtype=float)
    reach = h * (2 if stencil == 4 else 1)
    if lower is not None and np.min(x0 - lower) < reach:
        raise ValueError("x0 must lie at least h inside the lower bound")
    if upper is not None and np.min(upper - x0) < reach:
        raise ValueError("x0 must lie at least h inside the upper bound")
    an, nu, canc = [], [], []
    for _ in range(directions):
        for _try in range(50):
            d = rng.uniform(-1.0, 1.0, size=x0.shape)
            d /= np.max(np.abs(d))
            ratio = float(np.sum(np.abs(g * d)) / max(abs(float(g @ d)), 1e-300))
            if max_cancellation is None or ratio <= max_cancellation:
                break
        if stencil == 2:
            nu.append((fun(x0 + h * d) - fun(x0 - h * d)) / (2 * h))
        else:
            nu.append((fun(x0 - 2 * h * d) - 8 * fun(x0 - h * d) + 8 * fun(x0 + h * d)
                       - fun(x0 + 2 * h * d)) / (12 * h))
        an.append(float(g @ d))
        canc.append(ratio)
    an, nu = np.array(an), np.array(nu)
    scale = max(np.max(np.abs(an)), np.max(np.abs(nu)), 1e-300)
    rel = np.abs(an - nu) / np.maximum(np.maximum(np.abs(an), np.abs(nu)), 1e-12 * scale)
    return GradientCheck(an, nu, float(np.max(rel)), h, stencil, float(max(canc)))


def taylor_rates(fun: Callable[[np.ndarray], float], grad: Callable[[np.ndarray], np.ndarray],
                 x0: np.ndarray, *, h0: float = 1e-2, levels: int = 4, seed: int = 1) -> np.ndarray:
    """Convergence rates of the first-order Taylor remainder ``|f(x+h d) - f(x) - h g·d|``.

    For a correct gradient the remainder is O(h^2): the returned rates approach 2.  A wrong
    gradient gives rate 1.
    """
    rng = np.random.default_rng(seed)
    x0 = np.asarray(x0, dtype=float)
    d = rng.uniform(-1.0, 1.0, size=x0.shape)
    d /= np.max(np.abs(d))
    f0 = fun(x0)
    gd = float(np.asarray(grad(x0)) @ d)
    hs = h0 * 0.5 ** np.arange(levels)
    rem = np.array([abs(fun(x0 + h * d) - f0 - h * gd) for h in hs])
    return np.log(rem[:-1] / rem[1:]) / np.log(2.0)
