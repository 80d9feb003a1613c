"""Frictionless self-contact in a part's shape refinement: its term in the state, the adjoint
and the shape gradient of :class:`~pacto_ng.shape.gradient.PartResponse`.

The contact energy of the shape ``Ω = (id + d)(Ω0)`` is the penalty of
:mod:`pacto_ng.physics.contact` on the reference mesh ``Ω0``, at the positions
``X0 + d + u`` of its walls:

    E_c(u; d) = E0(u + P d),

``E0(w) = t ∫_Γc0 k/2 max(g(w), 0)² dA0`` with the gap ``g`` along the reference walls'
normals, and ``P`` the embedding of the shape's deformation (an order-1 VectorH1) in the
displacement's space: its vertex coefficients (NGSolve's H1 basis is hierarchical, a vertex's
function the P1 hat at every order).  The penalty thus treats the shape's motion as it treats
the displacement: the pairs are sought at ``X0 + d + u``, and the walls' normals and areas are
those of ``Ω0`` (the penalty's numerical weight; the refinement moves walls by fractions of an
element).  Then the residual's contact term is ``R_c(u; d)[v] = DE0(u + P d)[v]``, with the
pairs sought at ``u + P d``, and with ``J_c = ∂R_c/∂w`` its derivative in the walls'
positions ``w = u + P d``, the pairs' motion included,

    ∂/∂u R_c = J_c,    ∂/∂d R_c(u; d)[λ] = Pᵀ J_cᵀ λ,

so the adjoint's tangent is the body's plus ``J_c`` and the shape gradient's contact term is
``-Pᵀ J_cᵀ λ`` (the Lagrangian ``L = J - R(u; λ)`` of :mod:`pacto_ng.shape.gradient`).
NGSolve's ``ContactBoundary`` has no ``DiffShape`` (on ``Ω0`` none is needed), and its tangent
``H`` holds the pairs where the last pairing put them: ``J_c = H + C``, ``C`` the pairs'
motion (the paired point sliding along the other wall carries the contact force to other
dofs, a term of the order of the contact pressure over the modulus), which
:meth:`ShapeContact.pair_motion` adds by central differences of the residual paired anew.
Without ``C`` the gradient was 0.12 off at 30 kPa on a block of 1 MPa, and 5.7e-4 to 3.1e-3
at 3 kPa; with it, within 1.2e-7 of central differences of the re-solved state (pairs sought
anew at every shape: tests/shape/test_contact_gradient.py).  ``C`` costs two pairings per
colour of its columns (about 20-30 colours in 2D, 60 in 3D at order 1).

Every contact form is assembled with the mesh's deformation unset (on ``Ω0``) and the
deformation set again afterwards; its tangent, on a sparsity pattern of its own (the pairs
couple dofs of facing walls), is added to the body's as a sparse matrix (:class:`MatrixSum`:
the sum's pattern made once per pairing, its values summed at every Newton iteration).
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np
from ngsolve import VERTEX, BilinearForm, NodeId
from ngsolve.la import SparseMatrixd
from scipy.sparse import csr_matrix

from ..physics.contact import SelfContact, element_scale
from ..post.part_analysis import CONTACT_PENALTY, CONTACT_REACH


#: the step of the pairs' motion's central differences (:meth:`ShapeContact.pair_motion`), in
#: element sizes, well below the walls' overlap (about 1e-6 element sizes at 3 kPa on 1 MPa):
#: on the slotted block of tests/shape/test_contact_gradient.py 1e-7 and 1e-6 agree to 5e-9
#: and 1e-7 (linear, mixed), 1e-5 is 1.2e-2 off (its steps cross max(g, 0)²'s kink), 1e-8
#: 6e-7 (round-off); on the part of ``pacto refine DIR --check-gradients --contact`` (every
#: wall a candidate) 1e-6 left 4.6e-4 of Δ's derivative, 1e-7 3.8e-5 (2026-12-07)
MOTION_STEP = 1e-7


class MatrixSum:
    """``a + b`` of two sparse matrices in full storage, on the union of their sparsity
    patterns: made once per pair of patterns (NGSolve's ``CreateFromCOO``, 30-50 ms at 9e4
    entries), then only its values summed anew (:meth:`of`)."""

    def __init__(self):
        self.matrix, self._at = None, None

    def of(self, a, b) -> bool:
        """:attr:`matrix` = ``a + b``; whether the pattern is new (the last call's patterns
        unless :meth:`forget` was called since: a new factorisation, else a numeric one)."""
        parts = [tuple(np.asarray(p) for p in m.COO()) for m in (a, b)]
        rows, cols, vals = (np.concatenate([p[k] for p in parts]) for k in range(3))
        n = a.height
        new = self.matrix is None or len(vals) != len(self._at)  # (a pattern changed size)
        if new:  # the union pattern, rows sorted, and where each entry lands in it
            key = rows.astype(np.int64) * n + cols
            union = np.unique(key)
            self._at = np.searchsorted(union, key)
            self.matrix = SparseMatrixd.CreateFromCOO(union // n, union % n,
                                                      np.zeros(len(union)), n, n)
        values = self.matrix.AsVector().FV().NumPy()  # stored row by row, columns sorted
        values[:] = np.bincount(self._at, weights=vals, minlength=len(values))
        return new

    def forget(self) -> None:
        """The next sum is on new patterns."""
        self.matrix, self._at = None, None


class ShapeContact:
    """The walls ``names`` of the part in frictionless self-contact, on the reference mesh at
    the positions ``X0 + d + u`` (see the module).

    Parameters
    ----------
    fes : ngsolve FESpace
        The state's space on the part: the displacement's VectorH1, or one whose first
        component it is (see ``displacement``).
    space : ShapeSpace
        The shape's deformation ``d``: an order-1 space (its coefficients the vertices'
        motions).
    names : tuple of str
        The candidate walls.
    E1 : float
        The solid's modulus: the penalty is ``penalty E1 / h`` (h the mean element size of
        ``Ω0``) and pairs are sought within ``reach h``, as the part's analysis does
        (:class:`~pacto_ng.post.part_analysis.PartAnalysis`).
    thickness : float
        The 2D thickness (1 in 3D).
    displacement : callable, optional
        The displacement of a function of ``fes`` where ``fes`` holds more than it (the mixed
        formulation's state); default: ``fes`` is the displacement's space.
    """

    def __init__(self, fes, space, names, *, E1: float, thickness: float = 1.0,
                 penalty: float = CONTACT_PENALTY, reach: float = CONTACT_REACH,
                 displacement=None):
        if not space.vertex_dofs:
            raise ValueError("contact in the shape gradient needs an order-1 shape space (its "
                             "coefficients the vertices' motions)")
        self.mesh, self.space = fes.mesh, space
        with self._reference():
            self.contact = SelfContact.on_walls(fes, names, modulus=E1, penalty=penalty,
                                                reach=reach, thickness=thickness,
                                                displacement=displacement)
        self.form = BilinearForm(fes, symmetric=False)
        nodes = [NodeId(VERTEX, i) for i in range(self.mesh.nv)]
        self._u_dofs = np.array([fes.GetDofNrs(n) for n in nodes], dtype=np.int64).ravel()
        self._d_dofs = np.array([space.space.GetDofNrs(n) for n in nodes],
                                dtype=np.int64).ravel()
        self._w = {}  # a buffer per vector size: the state's, the displacement's (measure)
        self._sum = MatrixSum()
        self.new_pattern = True  # whether the last tangent_with made a new sparsity pattern
        with self._reference():
            self._step = MOTION_STEP * element_scale(self.mesh)
        self._motion = None  # C of the last with_motion (pair_motion), until the next pairing

    @contextmanager
    def _reference(self):
        """The mesh without its deformation (``Ω0``) for the duration."""
        self.mesh.UnsetDeformation()
        try:
            yield
        finally:
            self.mesh.SetDeformation(self.space.deformation)

    def _positions(self, vec):
        """``u + P d``: the displacement of the walls' points from ``Ω0`` (``vec`` a state
        or a displacement: the displacement's dofs come first in either)."""
        if len(vec) not in self._w:
            self._w[len(vec)] = vec.CreateVector()
        out = self._w[len(vec)]
        out.data = vec
        w = out.FV().NumPy()
        w[self._u_dofs] += self.space.deformation.vec.FV().NumPy()[self._d_dofs]
        return out

    def pair(self, vec) -> None:
        """Seek the pairs at the state ``vec`` (they hold until the next pairing)."""
        w = self._positions(vec)
        with self._reference():
            self.contact.update(self.form, w)
        self._sum.forget()  # the pairs couple other dofs: a new pattern
        self._motion = None

    def add_residual(self, vec, out) -> None:
        """``out += R_c(u; d)``, ``u`` = ``vec``, with the current pairs."""
        w, r = self._positions(vec), out.CreateVector()
        with self._reference():
            self.form.Apply(w, r)
        out.data += r

    def tangent(self, vec):
        """``H = D²E0(u + P d)`` at ``u`` = ``vec`` (the form's matrix, current pairs)."""
        w = self._positions(vec)
        with self._reference():
            self.form.AssembleLinearization(w)
        return self.form.mat

    def tangent_with(self, body, vec):
        """``body + H`` at ``u`` = ``vec`` (``body`` the body's tangent in full storage), the
        matrix kept for the pairing's next tangents (:attr:`new_pattern` says whether it
        is new)."""
        self.new_pattern = self._sum.of(body, self.tangent(vec))
        return self._sum.matrix

    def with_motion(self, vec):
        """``body + H + C`` at ``u`` = ``vec``: the matrix of the last :meth:`tangent_with`
        (at ``vec``) and the pairs' motion ``C`` (:meth:`pair_motion`), kept for
        :meth:`shape_term`: the derivative of the residual with the pairs sought anew."""
        self._motion = self.pair_motion(vec)
        if self._motion is None:
            return self._sum.matrix
        total = MatrixSum()
        total.of(self._sum.matrix, self._motion)
        return total.matrix

    def pair_motion(self, vec):
        """``C``: what the pairs' motion adds to ``∂R_c/∂u`` at ``u`` = ``vec`` (its pairs
        current, ``H`` of the last :meth:`tangent` at ``vec``), or None without pairs.  ``R_c`` pairs at the positions it is given; the
        tangent ``H`` holds them.  Each column of ``C`` is the central difference of ``R_c``
        paired anew at ``u ± ε e_j``, less that of ``R_c`` with the pairs held (``H e_j`` to
        the differences' own error, the kink of ``max(g, 0)²`` alike in both), for the
        columns of the dofs coupled to a pair in contact, several at once where no row of
        ``H``'s pattern joins them (Curtis, Powell & Reid 1974); ``ε`` = :data:`MOTION_STEP`
        element sizes.  The pairs are sought anew at ``vec`` at the end."""
        rows, cols, vals = (np.asarray(p) for p in self.form.mat.COO())  # H at vec
        touching = np.unique(rows[vals != 0.0])  # the dofs of pairs in contact
        keep = np.isin(rows, touching) | np.isin(cols, touching)
        rows, cols = rows[keep], cols[keep].astype(np.int64)
        if not len(cols):
            return None
        colour = column_colours(rows, cols)
        base = self._positions(vec)
        shifted, r = base.CreateVector(), base.CreateVector()
        held, moved = np.zeros(len(rows)), np.zeros(len(rows))
        entries = [colour[cols] == c for c in range(int(colour.max()) + 1)]  # one per row
        with self._reference():
            for anew, out in ((False, held), (True, moved)):  # every pairing anew last
                for at in entries:
                    group = np.unique(cols[at])
                    for sign in (1.0, -1.0):
                        shifted.data = base
                        shifted.FV().NumPy()[group] += sign * self._step
                        if anew:
                            self.contact.update(self.form, shifted)
                        self.form.Apply(shifted, r)
                        out[at] += sign * r.FV().NumPy()[rows[at]]
            self.contact.update(self.form, base)
        C = (moved - held) / (2 * self._step)
        n = len(vec)
        return SparseMatrixd.CreateFromCOO(rows, cols, C, n, n)

    def shape_term(self, lam) -> np.ndarray:
        """``Pᵀ (H + C)ᵀ λ`` on the shape space's coefficients (``H`` of the last
        :meth:`tangent`, ``C`` of the last :meth:`with_motion` since the last pairing), the
        held dofs zeroed: the shape derivative of ``R_c(u; d)[λ]``."""
        y = lam.CreateVector()
        y.data = self.form.mat * lam
        if self._motion is not None:
            y.data += self._motion.T * lam
        out = np.zeros(self.space.ndof)
        out[self._d_dofs] = y.FV().NumPy()[self._u_dofs]
        out[self.space.held] = 0.0
        return out

    def measure(self, vec) -> tuple[float, float, float]:
        """``(area, force, largest pressure)`` of the contact at the displacement ``vec``
        (:meth:`~pacto_ng.physics.contact.SelfContact.measure`)."""
        w = self._positions(vec)
        with self._reference():
            return self.contact.measure(w)


def column_colours(rows, cols) -> np.ndarray:
    """A colour per column (indexed by column number) such that no row has two columns of
    one colour: greedy, column by column."""
    n = int(max(rows.max(), cols.max())) + 1
    pattern = csr_matrix((np.ones(len(rows)), (cols, rows)), shape=(n, n))
    meets = (pattern @ pattern.T).tocsr()  # columns that share a row
    colour = np.full(n, -1)
    for j in np.unique(cols):
        taken = colour[meets.indices[meets.indptr[j]:meets.indptr[j + 1]]]
        free = np.setdiff1d(np.arange(len(taken) + 1), taken)
        colour[j] = free[0]
    return colour
