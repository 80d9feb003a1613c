"""One analysis of SoRoTop.m's and TOPress.m's set-ups (Kumar 2023), transcribed in numpy from
a reading of the published MATLAB sources (github.com/PrabhatIn/SoRoTop, .../TOPress) for the
tests, in the codes' own numbering, independent of pacto's mesh and blocks.

Numbering (0-based here): node n = i (nely+1) + j for column i = 0..nelx (x = i) and row
j = 0..nely counted from the TOP (y = nely - j); element e = i nely + j, its nodes
counter-clockwise from the lower left (i, j+1), (i+1, j+1), (i+1, j), (i, j); dofs 2n, 2n+1.
So a design given as a nely x nelx grid whose row 0 is the top row is ``grid.ravel("F")``.

Element matrices of a unit square (E = 1, t = 1): the 88-line code's stiffness (the codes'
Ke; tests/top88_reference.py) and, by 2x2 Gauss, the Laplace matrix (the codes' Kp), the mass
matrix (KDp) and T[2a+c, b] = ∫ N_a ∂_c N_b (the codes' Te, F = -T p), from
benchmarks/peer_pa_inverter.py.
"""
import os
import sys

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from benchmarks.peer_pa_inverter import _heaviside, q1_element_matrices  # noqa: E402
from top88_reference import q4_stiffness  # noqa: E402

#: the material and flow parameters both codes fix in their part 1 (element units)
E1, EMIN, NU, KV, EPSF, R, DELS = 1.0, 1e-6, 0.3, 1.0, 1e-7, 0.1, 2.0


class Grid:
    """The codes' nodes, elements and dof maps, and the sets named in their part 2."""

    def __init__(self, nelx, nely):
        self.nelx, self.nely = nelx, nely
        self.nno = (nelx + 1) * (nely + 1)
        node = lambda i, j: i * (nely + 1) + j
        i, j = np.meshgrid(np.arange(nelx), np.arange(nely), indexing="ij")
        i, j = i.ravel(), j.ravel()  # element e = i nely + j
        self.enod = np.stack([node(i, j + 1), node(i + 1, j + 1), node(i + 1, j), node(i, j)], 1)
        self.edof = np.repeat(2 * self.enod, 2, axis=1) + np.tile([0, 1], 4)
        self.col, self.row = i, j
        cols = np.arange(nelx + 1)
        rows = np.arange(nely + 1)
        self.left = node(0, rows)
        self.right = node(nelx, rows)
        self.top = node(cols, 0)
        self.bottom = node(cols, nely)

    def assemble(self, ke, coef, dofs):
        n = dofs.shape[1]
        rows = np.repeat(dofs, n, axis=1).ravel()
        cols = np.tile(dofs, n).ravel()
        return sp.csc_matrix((np.outer(coef, ke.ravel()).ravel(), (rows, cols)))


def analyse(grid, xphys, p_fixed, u_fixed, *, penal=3.0, etaf=0.2, betaf=10.0, kss=0.0,
            opdof=None):
    """Pressure, nodal forces and displacements of ρ̄ = ``xphys`` (the codes' part 9 / 6.1-6.2):
    ``p_fixed`` maps node -> prescribed pressure, ``u_fixed`` lists the fixed dofs."""
    Kp, KDp, T = (m for m in q1_element_matrices(NU)[1:])
    Ds = (np.log(R) / DELS) ** 2 * EPSF
    h = _heaviside(xphys, etaf, betaf)
    A = grid.assemble(Kp, KV * (1 - (1 - EPSF) * h), grid.enod) + grid.assemble(KDp, Ds * h,
                                                                                grid.enod)
    fixed = np.array(sorted(p_fixed))
    free = np.setdiff1d(np.arange(grid.nno), fixed)
    p = np.zeros(grid.nno)
    p[fixed] = [p_fixed[n] for n in fixed]
    p[free] = spla.spsolve(A[free][:, free].tocsc(), -A[free][:, fixed] @ p[fixed])
    rows = np.repeat(grid.edof, 4, axis=1).ravel()
    cols = np.tile(grid.enod, 8).ravel()
    TG = sp.csc_matrix((np.tile(T.ravel(), len(xphys)), (rows, cols)),
                       shape=(2 * grid.nno, grid.nno))
    F = -(TG @ p)
    E = EMIN + xphys ** penal * (E1 - EMIN)
    K0 = grid.assemble(q4_stiffness(NU), E, grid.edof)
    K = K0.tolil()
    if opdof is not None:
        K[opdof, opdof] += kss
    K = K.tocsc()
    ufree = np.setdiff1d(np.arange(2 * grid.nno), u_fixed)
    U = np.zeros(2 * grid.nno)
    U[ufree] = spla.spsolve(K[ufree][:, ufree].tocsc(), F[ufree])
    return p, F, U, K0, K


def sorotop(xphys, nelx, nely, *, kss=0.1, **kw):
    """SoRoTop.m on ρ̄ (its element order): u_x at the output node, ½UᵀK₀U (the structure's
    strain energy, without the spring) and UᵀKU (with it; the code's SE is half of this)."""
    g = Grid(nelx, nely)
    xphys = np.array(xphys, float)
    k = nely // 20
    xphys[(g.row < k) & (g.col < nelx // 20)] = 1.0  # NDS: the passive block
    p_fixed = {int(n): 0.0 for n in np.concatenate([g.top, g.right])}
    p_fixed.update({int(n): 1.0 for n in g.left})  # set last: the left corners at P_in
    u_fixed = np.concatenate([2 * g.top[:k], 2 * g.top[:k] + 1, 2 * g.bottom + 1])
    opdof = 2 * g.bottom[-1]
    p, F, U, K0, K = analyse(g, xphys, p_fixed, u_fixed, kss=kss, opdof=opdof, **kw)
    return dict(u_out=U[opdof], se=0.5 * U @ (K0 @ U), uku=U @ (K @ U), p=p, U=U, grid=g)


def topress(xphys, nelx, nely, **kw):
    """TOPress.m on ρ̄ (its element order): its objective, the compliance UᵀKU."""
    g = Grid(nelx, nely)
    p_fixed = {int(n): 0.0 for n in np.concatenate([g.top, g.left, g.right])}
    p_fixed.update({int(n): 1.0 for n in g.bottom})  # set last: the bottom corners at P_in
    b0, b1 = g.bottom[0], g.bottom[-1]
    u_fixed = np.array([2 * b0, 2 * b0 + 1, 2 * b1, 2 * b1 + 1])
    p, F, U, K0, K = analyse(g, np.asarray(xphys, float), p_fixed, u_fixed, **kw)
    return dict(compliance=U @ (K @ U), fu=F @ U, p=p, U=U, grid=g)
