"""MMA and GCMMA (Svanberg) from mmapy, with an external move limit.

Problem form: ``min f0(x)`` s.t. ``f_i(x) <= 0`` (i = 1..m), ``0 <= x <= 1``.  The move limit
``|x_new - x| <= move`` is imposed through the bounds handed to the subproblem.  The state
(previous iterates, asymptotes, GCMMA's ``raa``) is a plain dict of arrays so that a checkpoint
restores it exactly.

A worst-case objective ``min max_k f0_k(x)`` (``terms`` = K > 1, the robust formulation) is
solved in Svanberg's bound form: ``min z`` s.t. ``f0_k(x) + c - z <= 0`` (k = 1..K) and the
``f_i(x) <= 0``, i.e. mmapy's problem with objective 0, ``a0 = 1`` and ``a_i = 1`` for the K
bound constraints (``a_i = 0`` for the others).  MMA's ``z`` is non-negative, so the terms are
shifted by a constant ``c = 2 max_k |f0_k(x)| + 1`` of the current iterate (the same for
GCMMA's inner evaluations): the approximations of the shifted terms differ only in their
constant part, so the step is that of the unshifted problem as long as the worst term stays
above ``-c`` in the step (a drop of more than twice its size).
"""
from __future__ import annotations

import numpy as np


class Optimizer:
    """One MMA or GCMMA outer update per call of :meth:`update`.

    ``evaluate(x) -> (f0, fvals)`` (values only) is needed by GCMMA's inner loop; it returns
    None for a trial design that could not be analysed, and GCMMA then keeps its step.
    """

    def __init__(self, n: int, m: int, method: str = "mma", move: float = 0.1, terms: int = 1):
        if method not in ("mma", "gcmma"):
            raise ValueError(f"optimizer must be 'mma' or 'gcmma' (got '{method}')")
        if not 0 < move <= 1:
            raise ValueError("move limit must lie in (0, 1]")
        if terms < 1:
            raise ValueError(f"terms: the objective needs at least one term (got {terms})")
        self.terms = int(terms)
        bound = self.terms if self.terms > 1 else 0  # the bound constraints f0_k + c - z <= 0
        self.n, self.m, self.method, self.move = n, m + bound, method, move
        self.a0 = 1.0
        self.a = np.zeros((self.m, 1))
        self.a[:bound] = 1.0
        self.c = 1000.0 * np.ones((self.m, 1))
        self.d = np.ones((self.m, 1))
        self.state: dict | None = None
        self.inner_evaluations = 0

    def _bounds(self, x):
        return (np.maximum(0.0, x - self.move)[:, None], np.minimum(1.0, x + self.move)[:, None])

    def update(self, it: int, x: np.ndarray, f0: float, df0: np.ndarray, f: np.ndarray,
               df: np.ndarray, evaluate=None) -> np.ndarray:
        """Return the next design.  ``it`` counts from 1; ``df`` has shape (m, n).  With
        ``terms`` K > 1, ``f0`` holds the K terms of the worst case and ``df0`` has shape (K, n);
        ``evaluate`` then returns the K terms as its first value."""
        import mmapy

        if self.terms > 1:
            F0 = np.asarray(f0, dtype=float).reshape(self.terms)
            shift = 2.0 * float(np.max(np.abs(F0))) + 1.0
            f = np.concatenate([F0 + shift, np.asarray(f, dtype=float).ravel()])
            df = np.vstack([np.asarray(df0, dtype=float).reshape(self.terms, self.n),
                            np.asarray(df, dtype=float).reshape(-1, self.n)])
            f0, df0 = 0.0, np.zeros(self.n)

            def shaped(F0t, ft):
                return 0.0, np.concatenate([np.asarray(F0t, dtype=float).ravel() + shift,
                                            np.asarray(ft, dtype=float).ravel()])
        else:
            f0 = float(np.asarray(f0, dtype=float).ravel()[0])
            df0 = np.asarray(df0, dtype=float).reshape(self.n)

            def shaped(f0t, ft):
                return float(np.asarray(f0t, dtype=float).ravel()[0]), ft
        if evaluate is not None:
            inner = evaluate

            def evaluate(xt):
                trial = inner(xt)  # None: not analysed, GCMMA keeps its step (_gcmma)
                return None if trial is None else shaped(*trial)

        xval = x[:, None].astype(float)
        xmin, xmax = self._bounds(x)
        if self.state is None:
            self.state = dict(xold1=xval.copy(), xold2=xval.copy(), low=np.zeros((self.n, 1)),
                              upp=np.ones((self.n, 1)), raa0=0.01, raa=0.01 * np.ones((self.m, 1)))
        s = self.state
        fval = np.asarray(f, dtype=float).reshape(self.m, 1)
        dfdx = np.asarray(df, dtype=float).reshape(self.m, self.n)
        df0dx = np.asarray(df0, dtype=float)[:, None]
        if self.method == "mma":
            # global bounds [0, 1] for the asymptotes (Svanberg's scaling); the move limit
            # |x_new - x| <= move is mmasub's own bound alfa/beta = x ∓ move (xmax - xmin)
            zero, one = np.zeros((self.n, 1)), np.ones((self.n, 1))
            xmma, *_rest, low, upp = mmapy.mmasub(
                self.m, self.n, it, xval, zero, one, s["xold1"], s["xold2"], f0, df0dx, fval,
                dfdx, s["low"], s["upp"], self.a0, self.a, self.c, self.d, move=self.move)
            s["low"], s["upp"] = low, upp
        else:
            xmma = self._gcmma(it, xval, xmin, xmax, f0, df0dx, fval, dfdx, evaluate)
        s["xold2"], s["xold1"] = s["xold1"], xval.copy()
        return np.clip(xmma.ravel(), 0.0, 1.0)

    def _gcmma(self, it, xval, xmin, xmax, f0, df0dx, fval, dfdx, evaluate):
        import mmapy

        if evaluate is None:
            raise ValueError("GCMMA needs an evaluate(x) callback")
        s = self.state
        epsimin, raa0eps, raaeps = 1e-7, 1e-6, 1e-6 * np.ones((self.m, 1))
        low, upp, raa0, raa = mmapy.asymp(it, self.n, xval, s["xold1"], s["xold2"], xmin, xmax,
                                          s["low"], s["upp"], s["raa0"], s["raa"], raa0eps,
                                          raaeps, df0dx, dfdx)
        args = (self.a0, self.a, self.c, self.d)
        out = mmapy.gcmmasub(self.m, self.n, it, epsimin, xval, xmin, xmax, low, upp, raa0, raa,
                             np.array([[f0]]), df0dx, fval, dfdx, *args)
        xmma, f0app, fapp = out[0], out[9], out[10]
        for _ in range(15):
            trial = evaluate(xmma.ravel())
            if trial is None:  # the trial design could not be analysed: keep this step
                break
            f0new, fnew = trial
            self.inner_evaluations += 1
            f0new = np.array([[f0new]])
            fnew = np.asarray(fnew, dtype=float).reshape(self.m, 1)
            if mmapy.concheck(self.m, epsimin, f0app, f0new, fapp, fnew):
                break
            raa0, raa = mmapy.raaupdate(xmma, xval, xmin, xmax, low, upp, f0new, fnew, f0app,
                                        fapp, raa0, raa, raa0eps, raaeps, epsimin)
            out = mmapy.gcmmasub(self.m, self.n, it, epsimin, xval, xmin, xmax, low, upp, raa0,
                                 raa, np.array([[f0]]), df0dx, fval, dfdx, *args)
            xmma, f0app, fapp = out[0], out[9], out[10]
        s["low"], s["upp"], s["raa0"], s["raa"] = low, upp, raa0, raa
        return xmma
