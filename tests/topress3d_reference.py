"""One analysis of TOPress3D.m's set-up (Kumar 2024), transcribed in numpy/scipy from a reading
of the published MATLAB source (github.com/PrabhatIn/TOPress3D) for the tests, in the code's
own numbering, independent of pacto's mesh, spaces and forms.

Numbering (0-based here): node n = jy + (nely+1) kz + (nely+1)(nelz+1) ix for ix = 0..nelx,
jy = 0..nely, kz = 0..nelz, at x = ix, y = nely - jy (jy counts from y = nely down), z = kz;
element e = jy + nely kz + nely nelz ix, the cube [ix, ix+1] x [nely-jy-1, nely-jy] x
[kz, kz+1]; its nodes (jy+1, kz, ix), (jy+1, kz, ix+1), (jy, kz, ix+1), (jy, kz, ix) and the
same four at kz+1: in local coordinates (-,-,-), (+,-,-), (+,+,-), (-,+,-), then z = +.
Displacement dofs 3n, 3n+1, 3n+2 (x, y, z).

Element matrices of a unit cube by 2x2x2 Gauss quadrature (exact for these integrands): the
stiffness of E = 1, ν (isotropic 3D elasticity, Voigt order xx, yy, zz, xy, yz, xz), the
Laplace matrix Kp, the mass matrix KDp and T[3a+c, b] = ∫ N_a ∂_c N_b (F = -T p).
"""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy import ndimage

#: the material and flow parameters the code fixes in its part 1 (element units)
E1, EMIN, NU, KV, EPSF, R, DELS = 1.0, 1e-5, 0.3, 1.0, 1e-7, 0.1, 2.0
DS = (np.log(R) / DELS) ** 2 * EPSF  # drainage coefficient of solid
KVS = KV * (1.0 - EPSF)  # the flow coefficient's drop from void to solid

#: local node signs in the unit cube [-1, 1]^3
SIGNS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                  [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)


def h8_matrices(nu=NU):
    """``Ke (24x24), Kp (8x8), KDp (8x8), T (24x8)`` of a unit cube."""
    lam = nu / ((1 + nu) * (1 - 2 * nu))
    mu = 1.0 / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[:3, :3] += 2 * mu * np.eye(3)
    D[3:, 3:] = mu * np.eye(3)
    Ke, Kp, KDp, T = np.zeros((24, 24)), np.zeros((8, 8)), np.zeros((8, 8)), np.zeros((24, 8))
    gauss = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    for xi in np.array(np.meshgrid(gauss, gauss, gauss, indexing="ij")).reshape(3, -1).T:
        f = 1 + SIGNS * xi  # (8, 3)
        N = f.prod(axis=1) / 8
        # ∂N/∂x on the unit cube (x = (ξ + 1) / 2): twice ∂N/∂ξ
        dN = np.stack([SIGNS[:, c] * np.prod(np.delete(f, c, axis=1), axis=1) / 4
                       for c in range(3)], axis=1)
        w = 1.0 / 8  # the Gauss weights 1 times the Jacobian (1/2)^3
        B = np.zeros((6, 24))
        B[0, 0::3], B[1, 1::3], B[2, 2::3] = dN[:, 0], dN[:, 1], dN[:, 2]
        B[3, 0::3], B[3, 1::3] = dN[:, 1], dN[:, 0]
        B[4, 1::3], B[4, 2::3] = dN[:, 2], dN[:, 1]
        B[5, 0::3], B[5, 2::3] = dN[:, 2], dN[:, 0]
        Ke += w * B.T @ D @ B
        Kp += w * dN @ dN.T
        KDp += w * np.outer(N, N)
        for c in range(3):
            T[c::3, :] += w * np.outer(N, dN[:, c])
    return Ke, Kp, KDp, T


class Grid:
    """The code's nodes, elements and dof maps, and the faces named in its part 2."""

    def __init__(self, nelx, nely, nelz):
        self.nelx, self.nely, self.nelz = nelx, nely, nelz
        ndy, ndz = nely + 1, nelz + 1
        self.nno = (nelx + 1) * ndy * ndz
        self.nel = nelx * nely * nelz
        node = lambda ix, jy, kz: jy + ndy * kz + ndy * ndz * ix  # noqa: E731
        jy, kz, ix = (a.ravel("F") for a in np.meshgrid(np.arange(nely), np.arange(nelz),
                                                         np.arange(nelx), indexing="ij"))
        self.enod = np.stack([node(ix, jy + 1, kz), node(ix + 1, jy + 1, kz),
                              node(ix + 1, jy, kz), node(ix, jy, kz),
                              node(ix, jy + 1, kz + 1), node(ix + 1, jy + 1, kz + 1),
                              node(ix + 1, jy, kz + 1), node(ix, jy, kz + 1)], axis=1)
        self.edof = (3 * np.repeat(self.enod, 3, axis=1) + np.tile([0, 1, 2], 8))
        # element centres (x, y, z) and node coordinates
        self.centres = np.stack([ix + 0.5, nely - jy - 0.5, kz + 0.5], axis=1)
        n = np.arange(self.nno)
        nix, rest = np.divmod(n, ndy * ndz)
        nkz, njy = np.divmod(rest, ndy)
        self.coords = np.stack([nix, nely - njy, nkz], axis=1).astype(float)
        self.node_ijk = (nix, njy, nkz)
        top = nkz == nelz  # Tface: P_in
        self.top, self.bottom = np.flatnonzero(top), np.flatnonzero(nkz == 0)
        side = (nix == 0) | (nix == nelx) | (njy == 0) | (njy == nely)
        self.rim = np.flatnonzero(top & side)  # fixnn: the top face's rim, clamped

    def assemble(self, ke, coef, dofs, shape):
        n = dofs.shape[1]
        rows = np.repeat(dofs, n, axis=1).ravel()
        cols = np.tile(dofs, n).ravel()
        return sp.csc_matrix((np.outer(coef, ke.ravel()).ravel(), (rows, cols)), shape=shape)


def projection(x, eta, beta):
    """The code's smoothed Heaviside H(x; η, β) and its derivative."""
    den = np.tanh(beta * eta) + np.tanh(beta * (1 - eta))
    h = (np.tanh(beta * eta) + np.tanh(beta * (x - eta))) / den
    dh = beta * (1 - np.tanh(beta * (x - eta)) ** 2) / den
    return h, dh


def density_filter(x, nelx, nely, nelz, rmin):
    """The code's filter: imfilter of x (in its element order) with the cone kernel
    max(0, rmin - |d|), zero padding, divided by the filtered ones (part 4)."""
    c = int(np.ceil(rmin)) - 1
    d = np.arange(-c, c + 1)
    dy, dz, dx = np.meshgrid(d, d, d, indexing="ij")
    h = np.maximum(0.0, rmin - np.sqrt(dx ** 2 + dy ** 2 + dz ** 2))
    box = lambda v: ndimage.correlate(v.reshape((nely, nelz, nelx), order="F"), h,  # noqa: E731
                                      mode="constant", cval=0.0)
    return (box(np.asarray(x, float)) / box(np.ones(nely * nelz * nelx))).ravel("F")


def analyse(xphys, nelx, nely, nelz, *, penal=3.0, etaf=0.2, betaf=10.0, p_in=1.0):
    """Pressure, nodal forces, displacements, compliance UᵀF and its sensitivities with
    respect to ρ̄ = ``xphys`` (the code's element order; parts 3 and 6.1-6.3, lst = 1)."""
    g = Grid(nelx, nely, nelz)
    x = np.asarray(xphys, dtype=float)
    Ke, Kp, KDp, T = h8_matrices()
    h, dh = projection(x, etaf, betaf)
    A = (g.assemble(Kp, KV * (1 - (1 - EPSF) * h), g.enod, (g.nno, g.nno))
         + g.assemble(KDp, DS * h, g.enod, (g.nno, g.nno)))
    p = np.zeros(g.nno)
    p[g.top] = p_in  # the bottom face stays at 0
    fixed = np.union1d(g.top, g.bottom)
    free = np.setdiff1d(np.arange(g.nno), fixed)
    Aff = A[free][:, free].tocsc()
    p[free] = spla.spsolve(Aff, -A[free][:, fixed] @ p[fixed])
    rows = np.repeat(g.edof, 8, axis=1).ravel()
    cols = np.tile(g.enod, 24).ravel()
    TG = sp.csc_matrix((np.tile(T.ravel(), g.nel), (rows, cols)), shape=(3 * g.nno, g.nno))
    F = -(TG @ p)
    E = EMIN + x ** penal * (E1 - EMIN)
    K = g.assemble(Ke, E, g.edof, (3 * g.nno, 3 * g.nno))
    ufixed = np.concatenate([3 * g.rim, 3 * g.rim + 1, 3 * g.rim + 2])
    ufree = np.setdiff1d(np.arange(3 * g.nno), ufixed)
    U = np.zeros(3 * g.nno)
    U[ufree] = spla.spsolve(K[ufree][:, ufree].tocsc(), F[ufree])
    compliance = U @ F
    # sensitivities: the stiffness term and the load term through the adjoint of the flow
    # balance, Aff λ = 2 Tᵀ U on the free pressure dofs (λ = 0 on the given ones)
    ue = U[g.edof]
    d_stiff = -penal * (E1 - EMIN) * x ** (penal - 1) * np.einsum("ei,ij,ej->e", ue, Ke, ue)
    lam = np.zeros(g.nno)
    lam[free] = spla.spsolve(Aff, 2.0 * (TG[ufree][:, free].T @ U[ufree]))
    le, pe = lam[g.enod], p[g.enod]
    d_load = (-dh * KVS * np.einsum("ei,ij,ej->e", le, Kp, pe)
              + dh * DS * np.einsum("ei,ij,ej->e", le, KDp, pe))
    return dict(p=p, F=F, U=U, K=K, compliance=compliance, sens=d_stiff + d_load,
                volume=x.sum() / g.nel, grid=g, free=ufree)


def filter_sensitivity(g, nelx, nely, nelz, rmin):
    """The chain rule through :func:`density_filter` (the code's imfilter of g / Hs)."""
    c = int(np.ceil(rmin)) - 1
    d = np.arange(-c, c + 1)
    dy, dz, dx = np.meshgrid(d, d, d, indexing="ij")
    h = np.maximum(0.0, rmin - np.sqrt(dx ** 2 + dy ** 2 + dz ** 2))
    box = lambda v: ndimage.correlate(v.reshape((nely, nelz, nelx), order="F"), h,  # noqa: E731
                                      mode="constant", cval=0.0)
    hs = box(np.ones(nely * nelz * nelx)).ravel("F")
    return box(np.asarray(g, float) / hs).ravel("F")
