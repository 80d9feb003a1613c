"""Density filters and the Heaviside projection, as blocks on element-wise arrays.

* :class:`HelmholtzFilter` — PDE filter (thesis eqs A.5–A.6): ``-r_h² Δρ̃ + ρ̃ = x`` on H1
  order 1 with Neumann boundaries, ``r_h = R / (2√3)``; the nodal result is averaged back to
  the elements.  Forward ``ρ̃ = M⁻¹ Bᵀ A⁻¹ B x`` with the mixed mass matrix ``B`` (L2-0 → H1),
  the element areas ``M``; backward is the transpose, reusing the one factorisation of ``A``.
* :class:`ConeFilter` — the classic distance-weighted density filter (thesis eqs A.3–A.4):
  ``ρ̃_i = Σ_j w_ij v_j x_j / Σ_j w_ij v_j`` with ``w_ij = max(0, R - |c_i - c_j|)``.
* :class:`HeavisideProjection` — ``ρ̄ = H(ρ̃; η, β)`` (thesis eq. A.7); ``beta`` is mutable
  for continuation.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .interpolation import heaviside_deriv_np, heaviside_np
from .physics.solvers import LinearSolver


class HelmholtzFilter:
    """Helmholtz PDE filter with cone-equivalent radius ``R`` (``r_h = R / (2√3)``).

    ``solver``: ``auto``, ``direct`` or ``iterative``, the route of the filter's system
    (:class:`~pacto_ng.physics.solvers.LinearSolver`: sparse Cholesky, or CG with ``h1amg``;
    :attr:`solver_info`)."""

    def __init__(self, mesh, radius: float, inputs=("rho",), output="rho_tilde",
                 solver: str = "auto"):
        from ngsolve import H1, L2, BilinearForm, GridFunction, Integrate, grad, dx

        if radius <= 0:
            raise ValueError("filter radius must be positive")
        self.inputs, self.output = tuple(inputs), output
        self.radius = radius
        rh = radius / (2.0 * np.sqrt(3.0))
        self.fes = H1(mesh, order=1)
        self.l2 = L2(mesh, order=0)
        u, v = self.fes.TnT()
        q = self.l2.TrialFunction()
        a = BilinearForm(self.fes, symmetric=True)
        a += (rh ** 2 * grad(u) * grad(v) + u * v) * dx
        self._solver = LinearSolver(a, setting=solver)
        a.Assemble()
        b = BilinearForm(trialspace=self.l2, testspace=self.fes)
        b += q * v * dx
        b.Assemble()
        self.a, self.b = a, b
        self._solver.prepare()
        self.areas = np.array(Integrate(1.0, mesh, element_wise=True))
        self._gx = GridFunction(self.l2)
        self._rhs = a.mat.CreateColVector()
        self._sol = a.mat.CreateColVector()

    def _apply(self, xe: np.ndarray) -> np.ndarray:
        """``M⁻¹ Bᵀ A⁻¹ B xe`` (the operator is symmetric up to the area weights)."""
        self._gx.vec.FV().NumPy()[:] = xe
        self._rhs.data = self.b.mat * self._gx.vec
        self._solver.solve(self._rhs, self._sol)
        out = self._gx.vec.CreateVector()
        out.data = self.b.mat.T * self._sol
        return out.FV().NumPy().copy()

    @property
    def solver_info(self) -> dict:
        """The filter's linear solver, for the run summary
        (:attr:`~pacto_ng.physics.solvers.LinearSolver.info`)."""
        return self._solver.info

    def forward(self, x):
        return self._apply(np.asarray(x, dtype=float)) / self.areas

    def backward(self, g):
        # ρ̃ = M⁻¹ Bᵀ A⁻¹ B x  ⇒  dJ/dx = Bᵀ A⁻¹ B M⁻¹ g  (A symmetric)
        return (self._apply(np.asarray(g, dtype=float) / self.areas),)


class ConeFilter:
    """Classic distance-weighted (cone) density filter of radius ``R``, volume weighted."""

    def __init__(self, centroids: np.ndarray, areas: np.ndarray, radius: float,
                 inputs=("rho",), output="rho_tilde"):
        from scipy.spatial import cKDTree

        if radius <= 0:
            raise ValueError("filter radius must be positive")
        self.inputs, self.output = tuple(inputs), output
        c = np.asarray(centroids, dtype=float)  # (elements, dimension)
        tree = cKDTree(c)
        d = tree.sparse_distance_matrix(tree, radius, output_type="coo_matrix")
        w = radius - d.data
        keep = w > 0
        off = keep & (d.row != d.col)
        W = sp.coo_matrix((w[off], (d.row[off], d.col[off])), shape=(len(c), len(c))).tocsr()
        W = W + sp.diags(np.full(len(c), radius))  # each element's own weight, R - 0
        W = W @ sp.diags(areas)
        self.P = sp.diags(1.0 / np.asarray(W.sum(axis=1)).ravel()) @ W
        self.PT = self.P.T.tocsr()

    def forward(self, x):
        return self.P @ np.asarray(x, dtype=float)

    def backward(self, g):
        return (self.PT @ np.asarray(g, dtype=float),)


class IdentityFilter:
    """No filtering (``ρ̃ = ρ``)."""

    def __init__(self, inputs=("rho",), output="rho_tilde"):
        self.inputs, self.output = tuple(inputs), output

    def forward(self, x):
        return np.array(x, dtype=float)

    def backward(self, g):
        return (np.array(g, dtype=float),)


class HeavisideProjection:
    """Element-wise projection ``ρ̄ = H(ρ̃; η, β)``; ``beta = 0`` is the identity."""

    def __init__(self, beta: float = 1.0, eta: float = 0.5, inputs=("rho_tilde",), output="rho_proj"):
        if not 0.0 < eta < 1.0:
            raise ValueError("projection eta must lie in (0, 1)")
        if beta < 0:
            raise ValueError("projection beta must be >= 0")
        self.beta, self.eta = float(beta), float(eta)
        self.inputs, self.output = tuple(inputs), output
        self._rho = None

    def forward(self, rho):
        self._rho = np.asarray(rho, dtype=float).copy()
        return heaviside_np(self._rho, self.eta, self.beta)

    def backward(self, g):
        return (np.asarray(g, dtype=float) * heaviside_deriv_np(self._rho, self.eta, self.beta),)
