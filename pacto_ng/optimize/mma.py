"""MMA and GCMMA (Svanberg) from mmapy, with an external move limit.

Problem form: ``min f0(x)`` s.t. ``f_i(x) <= 0`` (i = 1..m), ``0 <= x <= 1``.  The move limit
``|x_new - x| <= move`` is imposed through the bounds handed to the subproblem.  The state
(previous iterates, asymptotes, GCMMA's ``raa``) is a plain dict of arrays so that a checkpoint
restores it exactly.
"""
from __future__ import annotations

import numpy as np


class Optimizer:
    """One MMA or GCMMA outer update per call of :meth:`update`.

    ``evaluate(x) -> (f0, fvals)`` (values only) is needed by GCMMA's inner loop.
    """

    def __init__(self, n: int, m: int, method: str = "mma", move: float = 0.1):
        if method not in ("mma", "gcmma"):
            raise ValueError(f"optimizer must be 'mma' or 'gcmma' (got '{method}')")
        if not 0 < move <= 1:
            raise ValueError("move limit must lie in (0, 1]")
        self.n, self.m, self.method, self.move = n, m, method, move
        self.a0 = 1.0
        self.a = np.zeros((m, 1))
        self.c = 1000.0 * np.ones((m, 1))
        self.d = np.ones((m, 1))
        self.state: dict | None = None
        self.inner_evaluations = 0

    def _bounds(self, x):
        return (np.maximum(0.0, x - self.move)[:, None], np.minimum(1.0, x + self.move)[:, None])

    def update(self, it: int, x: np.ndarray, f0: float, df0: np.ndarray, f: np.ndarray,
               df: np.ndarray, evaluate=None) -> np.ndarray:
        """Return the next design.  ``it`` counts from 1; ``df`` has shape (m, n)."""
        import mmapy

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
            f0new, fnew = evaluate(xmma.ravel())
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
