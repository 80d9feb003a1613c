"""Sparse matrices that are linear in element-wise coefficients, from precomputed element matrices.

A bilinear form whose integrand is ``Σ_k c_k(e) a_k(u, v)`` with element-wise constant
coefficients ``c_k`` (SIMP: ``E(ρ̄_e)`` times the unit-modulus elasticity; Darcy: ``K(ρ̄_e)``
times the Laplacian plus ``D(ρ̄_e)`` times the mass) has the matrix

    ``A(c) = A_0 + Σ_k Σ_e c_k(e) A_{k,e}``,

with fixed element matrices ``A_{k,e}`` and a constant part ``A_0`` (springs).  The values of
``A`` (in the storage order of NGSolve's sparse matrix) are then ``v_0 + Σ_k S_k c_k`` with
sparse ``S_k`` (one column per element) computed once; a new design costs a sparse product
instead of a numerical integration (measured, 120 x 80 Q1 elasticity: 25 ms against 1 ms).
The element quadratic forms the sensitivities need, ``x_eᵀ A_{k,e} y_e`` for every element,
are ``S_kᵀ w`` with ``w`` the products ``x_i y_j`` of the stored entries.

``S_k`` is found by assembling the form itself with ``c_k`` the indicator of a set of elements
that share no vertex (a colouring): every stored entry then belongs to one element of the set.
That costs one assembly per colour and term: 4-12 colours on triangles and quadrilaterals, 8
on structured hexahedra, but 50 on 4618 Netgen tetrahedra, where the colours took 35 s of a
PneuNet's first design.  Above :data:`MAX_COLOURS` colours the element matrices are computed
element by element instead, from the form's volume integrators (``CalcElementMatrix``; 0.26 s
for the same 4618 tetrahedra against 0.15 s per assembly, measured 2026-12-03).  Either way
the result is checked against a direct assembly with random coefficients before it is used.
Nothing else depends on the dimension.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..parallel import distributed


#: above this many colours the element matrices come element by element (module docstring)
MAX_COLOURS = 16

_last_colouring = (None, None)  # (mesh, colours): the blocks of one problem share a mesh


def element_colours(mesh) -> np.ndarray:
    """A colour per volume element such that elements of one colour share no vertex (greedy).
    The last mesh's colouring is kept (NGSolve meshes cannot be weakly referenced or hashed)."""
    global _last_colouring
    from ngsolve import VOL

    if _last_colouring[0] is mesh:
        return _last_colouring[1]

    verts = [[v.nr for v in el.vertices] for el in mesh.Elements(VOL)]
    ne = len(verts)
    lens = np.fromiter((len(v) for v in verts), int, ne)
    E = sp.csr_matrix((np.ones(lens.sum()), (np.repeat(np.arange(ne), lens),
                                            np.concatenate(verts))), shape=(ne, mesh.nv))
    adj = (E @ E.T).tocsr()
    colour = np.full(ne, -1)
    ip, ind = adj.indptr, adj.indices
    for e in range(ne):
        used = set(colour[ind[ip[e]:ip[e + 1]]].tolist())
        c = 0
        while c in used:
            c += 1
        colour[e] = c
    _last_colouring = (mesh, colour)
    return colour


def element_dofs(fes):
    """``(dofs, elements)``: the dof numbers of every volume element, flattened, and the element
    each belongs to."""
    from ngsolve import VOL, ElementId

    ne = fes.mesh.ne
    per = [np.asarray(fes.GetDofNrs(ElementId(VOL, e)), dtype=np.int64) for e in range(ne)]
    per = [d[d >= 0] for d in per]
    return (np.concatenate(per), np.repeat(np.arange(ne), [len(d) for d in per]),
            max(len(d) for d in per))


class ElementMatrices:
    """``form.mat = A_0 + Σ_k Σ_e c_k(e) A_{k,e}`` for element-wise coefficients ``c_k``.

    Parameters
    ----------
    form : ngsolve.BilinearForm
        The form; its matrix is written in place by :meth:`assemble`.
    set_coefficients : callable ``(list of nterms arrays of length ne) -> None``
        Sets the form's coefficient fields so that its integrand is ``Σ_k c_k a_k``.
    nterms : int
    max_entries : int
        Above this many entries of the ``S_k`` together (about 12 bytes each), :meth:`build`
        returns None (the memory of high orders on fine meshes), and the form is assembled as
        before.  The build costs one assembly per colour and term (4-12 colours in 2D, 8 on
        structured hexahedra), or, above :data:`MAX_COLOURS` colours (Netgen tetrahedra: 22
        for 157 elements, 46 for 851), two element-by-element passes per term.

    A form that is not of this kind (an entry no single element explains, or the check against
    NGSolve's assembly with random coefficients) raises ``ValueError``: the caller declared it.
    """

    def __init__(self, form, values, v0, rows, cols, S, lower):
        self.form, self.values, self.v0 = form, values, v0
        self.rows, self.cols, self.S, self.lower = rows, cols, S, lower
        self._off = rows != cols

    @classmethod
    def build(cls, form, fes, set_coefficients, nterms, *, volume=None,
              max_entries=20_000_000, tol=1e-12, seed=8642):
        """The element matrices of ``form`` (None above ``max_entries``, and on a distributed
        mesh, :mod:`pacto_ng.parallel`).  ``volume``: the
        form's integrators over the volume elements, those whose element matrices carry the
        coefficients (None: all of them); used when the colouring has more than
        :data:`MAX_COLOURS` colours."""
        mesh = fes.mesh
        ne = mesh.ne
        if distributed(mesh):  # each rank would colour and assemble its part differently
            return None
        dofs, owners, nmax = element_dofs(fes)
        if nterms * ne * nmax * nmax > max_entries:
            return None
        zero = [np.zeros(ne) for _ in range(nterms)]
        set_coefficients(zero)
        form.Assemble()
        mat = form.mat
        values = mat.AsVector().FV().NumPy()  # a view: writing it writes the matrix
        v0 = values.copy()
        _, ind, ip = mat.CSR()  # (values, column indices, row pointers), as scipy's
        index = np.int32 if fes.ndof < 2**31 else np.int64  # (half the memory where it fits)
        ip, cols = np.array(ip, dtype=np.int64), np.array(ind, dtype=index)
        rows = np.repeat(np.arange(len(ip) - 1, dtype=index), np.diff(ip))
        if len(rows) != len(values):
            raise ValueError("ElementMatrices: the matrix's CSR structure does not match its "
                             "values")
        lower = bool(np.all(cols <= rows))  # symmetric storage: the lower triangle only
        colour = element_colours(mesh)
        if colour.max() + 1 > MAX_COLOURS:
            S = _element_by_element(form if volume is None else volume, fes, set_coefficients,
                                    nterms, rows, cols, lower)
        else:
            S = cls._by_colours(form, fes, set_coefficients, nterms, values, v0, rows, cols,
                                colour, dofs, owners)
        out = cls(form, values, v0, rows, cols, S, lower)
        # the check: random coefficients, assembled by NGSolve and by the scatter
        rng = np.random.default_rng(seed)
        c = [rng.uniform(0.1, 1.0, ne) for _ in range(nterms)]
        set_coefficients(c)
        form.Assemble()
        ref = values.copy()
        out.assemble(c)
        scale = max(float(np.max(np.abs(ref))), 1e-300)
        if not np.max(np.abs(values - ref)) <= tol * scale:
            raise ValueError(f"ElementMatrices: the scattered matrix differs from NGSolve's "
                             f"assembly by {np.max(np.abs(values - ref)) / scale:.2e} (relative)")
        return out

    @staticmethod
    def _by_colours(form, fes, set_coefficients, nterms, values, v0, rows, cols, colour, dofs,
                    owners):
        """``S_k`` from one assembly per colour and term (the module docstring)."""
        ne = fes.mesh.ne
        zero = [np.zeros(ne) for _ in range(nterms)]
        parts = [([], [], []) for _ in range(nterms)]  # (entries, elements, values) per term
        for col in range(colour.max() + 1):
            # the element of this colour that owns each dof (-1: none), and the stored entries
            # whose row and column belong to one such element
            sel = colour[owners] == col
            owner = np.full(fes.ndof, -1)
            owner[dofs[sel]] = owners[sel]
            mine = (owner[rows] >= 0) & (owner[rows] == owner[cols])
            indicator = (colour == col).astype(float)
            for k in range(nterms):
                ind_c = [z.copy() for z in zero]
                ind_c[k] = indicator
                set_coefficients(ind_c)
                form.Assemble()
                dv = values - v0
                if np.any(dv[~mine] != 0.0):
                    set_coefficients(zero)
                    raise ValueError("ElementMatrices: an entry no single element explains "
                                     "(the form is not Σ c_k a_k with element-wise c_k)")
                nz = np.flatnonzero(mine & (dv != 0.0))
                parts[k][0].append(nz)
                parts[k][1].append(owner[rows[nz]])
                parts[k][2].append(dv[nz])
        return [sp.csr_matrix((np.concatenate(d_), (np.concatenate(r_), np.concatenate(c_))),
                              shape=(len(values), ne)) for r_, c_, d_ in parts]

    def assemble(self, coeffs):
        """Write ``A(c)`` into the form's matrix."""
        v = self.v0.copy()
        for S, c in zip(self.S, coeffs):
            v += S @ c
        self.values[:] = v

    def quadratic(self, x, y):
        """``[x_eᵀ A_{k,e} y_e for every element e]`` for each term ``k`` (numpy dof vectors)."""
        w = x[self.rows] * y[self.cols]
        if self.lower:
            w[self._off] += x[self.cols[self._off]] * y[self.rows[self._off]]
        return [S.T @ w for S in self.S]


def _element_by_element(integrators, fes, set_coefficients, nterms, rows, cols, lower,
                        chunk=2048):
    """``S_k`` from the element matrices of the volume ``integrators`` with ``c_k = 1`` less
    those with every coefficient 0 (a part that carries no coefficient; computed only where the
    first element has one), ``chunk`` elements at a time, placed at the stored entries
    ``(rows, cols)`` of the form's matrix (CSR order, each entry once).  ``S_k`` in compressed
    columns, one per element, sharing their structure; written into arrays of their final size
    (at 228,318 dofs, 45.5 million entries, 12 bytes each)."""
    from ngsolve import VOL, ElementId

    mesh = fes.mesh
    ne, n = mesh.ne, fes.ndof
    integrators = list(getattr(integrators, "integrators", integrators))
    # 1 + the index of each stored entry, in the matrix's structure (0: not stored)
    start_of = np.concatenate(([0], np.cumsum(np.bincount(rows, minlength=n))))
    index = sp.csr_matrix((np.arange(1, cols.size + 1, dtype=np.int64 if cols.size >= 2**31
                                     else np.int32), cols, start_of), shape=(n, n))

    def matrix(e):
        ei = ElementId(VOL, e)
        fel, trafo = fes.GetFE(ei), mesh.GetTrafo(ei)
        return sum(bfi.CalcElementMatrix(fel, trafo).NumPy() for bfi in integrators)

    set_coefficients([np.zeros(ne) for _ in range(nterms)])
    base = [None] * ne
    if np.any(matrix(0) != 0.0):
        base = [matrix(e) for e in range(ne)]
    dofs = [np.asarray(fes.GetDofNrs(ElementId(VOL, e)), dtype=np.int64) for e in range(ne)]
    chunks = []  # (start, stop): elements with as many dofs as the first
    for e in range(ne):
        if not chunks or e - chunks[-1][0] >= chunk or dofs[e].size != dofs[chunks[-1][0]].size:
            chunks.append((e, e + 1))
        else:
            chunks[-1] = (chunks[-1][0], e + 1)

    def stored(start, stop):  # the elements' dofs, and which of their pairs are stored
        d = np.array(dofs[start:stop])
        keep = (d[:, :, None] >= 0) & (d[:, None, :] >= 0)
        if lower:
            keep &= d[:, :, None] >= d[:, None, :]
        return d, keep

    counts = np.zeros(ne, dtype=np.int64)
    for start, stop in chunks:
        counts[start:stop] = stored(start, stop)[1].sum(axis=(1, 2))
    indptr = np.concatenate(([0], np.cumsum(counts)))
    indices = np.empty(indptr[-1], dtype=np.int32 if cols.size < 2**31 else np.int64)
    data = [np.empty(indptr[-1]) for _ in range(nterms)]
    for k in range(nterms):
        indicator = [np.zeros(ne) for _ in range(nterms)]
        indicator[k] = np.ones(ne)
        set_coefficients(indicator)
        for start, stop in chunks:
            d, keep = stored(start, stop)
            e, i, j = np.nonzero(keep)  # the element, row and column of each entry stored
            at = slice(indptr[start], indptr[stop])
            if k == 0:
                pos = np.asarray(index[d[e, i], d[e, j]]).ravel()
                if np.any(pos == 0):
                    raise ValueError("ElementMatrices: an element couples dofs the matrix does "
                                     "not store")
                indices[at] = pos - 1
            m = np.array([matrix(el) if base[el] is None else matrix(el) - base[el]
                          for el in range(start, stop)])
            data[k][at] = m[e, i, j]
    return [sp.csc_matrix((v, indices, indptr), shape=(len(rows), ne)) for v in data]
