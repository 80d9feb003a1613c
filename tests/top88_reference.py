"""The classic 88-line code's bilinear Q4 element (plane stress, unit square) and its global
compliance, written independently in numpy for comparison with the NGSolve discretisation.

KE is the closed-form stiffness of a unit Q4 element with full 2x2 Gauss integration
(Andreassen et al. 2011, eq. in the 88-line code).  Node order: lower-left, lower-right,
upper-right, upper-left (counter-clockwise); dofs (u_x, u_y) per node.
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

#: ``pacto run mbb`` options for the 88-line code's optimisation (p = 3 throughout, no
#: projection, move limit 0.2) in place of the case's default, the library's continuation
TOP88_OPTIMISER = ["--set", "penal=3", "--set", "beta=0", "--set", "move=0.2"]


def q4_stiffness(nu):
    """The 88-line code's KE for E = 1 (its node order: LL, LR, UR, UL counter-clockwise
    when y points up)."""
    A11 = np.array([[12, 3, -6, -3], [3, 12, 3, 0], [-6, 3, 12, -3], [-3, 0, -3, 12]])
    A12 = np.array([[-6, -3, 0, 3], [-3, -6, -3, -6], [0, -3, -6, 3], [3, -6, 3, -6]])
    B11 = np.array([[-4, 3, -2, 9], [3, -4, -9, 4], [-2, -9, -4, -3], [9, 4, -3, -4]])
    B12 = np.array([[2, -3, 4, -9], [-3, 2, 9, -2], [4, 9, 2, 3], [-9, -2, 3, 2]])
    KE = 1 / (1 - nu ** 2) / 24 * (np.block([[A11, A12], [A12.T, A11]])
                                     + nu * np.block([[B11, B12], [B12.T, B11]]))
    return KE


def q4_stiffness_gauss(nu):
    """The same element integrated numerically (2x2 Gauss) from the bilinear shape functions,
    node order LL, LR, UR, UL, dofs interleaved (ux0, uy0, ux1, ...)."""
    D = 1 / (1 - nu ** 2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])
    xi = np.array([-1, 1, 1, -1.0]) / 1.0
    eta = np.array([-1, -1, 1, 1.0])
    g = 1 / np.sqrt(3)
    K = np.zeros((8, 8))
    for a in (-g, g):
        for b in (-g, g):
            dN_dxi = 0.25 * xi * (1 + eta * b)
            dN_deta = 0.25 * eta * (1 + xi * a)
            # unit square: x = (1+xi)/2 -> dxi/dx = 2; detJ = 1/4
            dNx, dNy = 2 * dN_dxi, 2 * dN_deta
            B = np.zeros((3, 8))
            B[0, 0::2] = dNx
            B[1, 1::2] = dNy
            B[2, 0::2] = dNy
            B[2, 1::2] = dNx
            K += B.T @ D @ B * 0.25
    return K


def mbb_compliance(rho_grid, nu=0.3, penal=3.0, Emin=1e-9, E0=1.0, F=-1.0):
    """Compliance of the half MBB beam (88-line code set-up) for a nely x nelx density grid
    whose row 0 is the *top* row of elements.  Mesh with y pointing up; node (i, j) is column
    i, row j from the bottom."""
    nely, nelx = rho_grid.shape
    KE = q4_stiffness_gauss(nu)
    nid = lambda i, j: j * (nelx + 1) + i
    ndof = 2 * (nelx + 1) * (nely + 1)
    rows, cols, vals = [], [], []
    for jr in range(nely):  # jr: row from the top
        j = nely - 1 - jr
        for i in range(nelx):
            nodes = [nid(i, j), nid(i + 1, j), nid(i + 1, j + 1), nid(i, j + 1)]
            dofs = np.ravel([[2 * n, 2 * n + 1] for n in nodes])
            E = Emin + rho_grid[jr, i] ** penal * (E0 - Emin)
            rows.append(np.repeat(dofs, 8))
            cols.append(np.tile(dofs, 8))
            vals.append((E * KE).ravel())
    K = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(ndof, ndof)).tocsc()
    f = np.zeros(ndof)
    f[2 * nid(0, nely) + 1] = F  # top-left corner, downwards
    fixed = [2 * nid(0, j) for j in range(nely + 1)] + [2 * nid(nelx, 0) + 1]
    free = np.setdiff1d(np.arange(ndof), fixed)
    u = np.zeros(ndof)
    u[free] = spla.spsolve(K[free][:, free], f[free])
    return float(f @ u)


def top88(nelx=60, nely=20, volfrac=0.5, penal=3.0, rmin=1.5, ft=1, maxiter=2000, nu=0.3):
    """The 88-line code (Andreassen et al. 2011) in numpy: OC updates, density (ft=1) or
    sensitivity (ft=0) filter, stops when the largest change falls below 0.01.  Element
    numbering as in MATLAB: column-major from the top-left, y downwards.  Returns (x, c, its)."""
    E0, Emin = 1.0, 1e-9
    KE = q4_stiffness(nu)
    nodenrs = np.arange((1 + nelx) * (1 + nely)).reshape((1 + nelx, 1 + nely)).T  # MATLAB reshape
    edofVec = (2 * nodenrs[:-1, :-1] + 2).T.ravel()  # MATLAB 1-based +1 -> here 0-based +2
    off = np.array([0, 1, 2 * nely + 2, 2 * nely + 3, 2 * nely + 0, 2 * nely + 1, -2, -1])
    edofMat = edofVec[:, None] + off[None, :]
    iK = np.kron(edofMat, np.ones((8, 1))).ravel().astype(int)
    jK = np.kron(edofMat, np.ones((1, 8))).ravel().astype(int)
    ndof = 2 * (nely + 1) * (nelx + 1)
    F = np.zeros(ndof)
    F[1] = -1.0
    fixed = np.union1d(np.arange(0, 2 * (nely + 1), 2), [ndof - 1])
    free = np.setdiff1d(np.arange(ndof), fixed)
    # filter
    rows, cols, vals = [], [], []
    R = int(np.ceil(rmin)) - 1
    for i1 in range(nelx):
        for j1 in range(nely):
            e1 = i1 * nely + j1
            for i2 in range(max(i1 - R, 0), min(i1 + R + 1, nelx)):
                for j2 in range(max(j1 - R, 0), min(j1 + R + 1, nely)):
                    e2 = i2 * nely + j2
                    rows.append(e1)
                    cols.append(e2)
                    vals.append(max(0.0, rmin - np.hypot(i1 - i2, j1 - j2)))
    H = sp.coo_matrix((vals, (rows, cols)), shape=(nelx * nely, nelx * nely)).tocsr()
    Hs = np.asarray(H.sum(axis=1)).ravel()
    x = np.full(nely * nelx, volfrac)
    xPhys = x.copy()
    change, loop, c = 1.0, 0, 0.0
    while change > 0.01 and loop < maxiter:
        loop += 1
        sK = (KE.ravel()[None, :] * (Emin + xPhys[:, None] ** penal * (E0 - Emin))).ravel()
        K = sp.coo_matrix((sK, (iK, jK)), shape=(ndof, ndof)).tocsc()
        K = (K + K.T) / 2
        U = np.zeros(ndof)
        U[free] = spla.spsolve(K[free][:, free], F[free])
        ce = np.einsum("ij,jk,ik->i", U[edofMat], KE, U[edofMat])
        c = float(((Emin + xPhys ** penal * (E0 - Emin)) * ce).sum())
        dc = -penal * (E0 - Emin) * xPhys ** (penal - 1) * ce
        dv = np.ones(nely * nelx)
        if ft == 0:
            dc = H @ (x * dc) / Hs / np.maximum(1e-3, x)
        else:
            dc = H @ (dc / Hs)
            dv = H @ (dv / Hs)
        l1, l2, move = 0.0, 1e9, 0.2
        while (l2 - l1) / (l1 + l2) > 1e-3:
            lmid = 0.5 * (l2 + l1)
            xnew = np.maximum(0, np.maximum(x - move, np.minimum(1, np.minimum(
                x + move, x * np.sqrt(-dc / dv / lmid)))))
            xPhys = xnew if ft == 0 else (H @ xnew) / Hs
            if xPhys.sum() > volfrac * nelx * nely:
                l1 = lmid
            else:
                l2 = lmid
        change = float(np.abs(xnew - x).max())
        x = xnew
    return xPhys, c, loop, x
