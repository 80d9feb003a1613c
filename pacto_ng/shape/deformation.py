"""The shape of a part as a deformation of its mesh, and shape derivatives on it.

The part's reference mesh Ω0 is moved by a deformation ``d`` in a VectorH1 space ``X`` of the
mesh (order 1 by default): the current shape is ``Ω = (id + d)(Ω0)``, set with NGSolve's
``mesh.SetDeformation``, so that every form assembled afterwards integrates over Ω.  A
functional ``J(Ω) = ∫_Ω f dx + ∫_∂Ω g ds`` has the shape derivative in a direction
``V ∈ X`` (Hadamard; Sokolowski and Zolésio 1992, *Introduction to Shape Optimization*, §2.31
and §2.33; Allaire, Dapogny and Jouve 2021, *Handbook of Numerical Analysis* 22, "Shape and
topology optimization", eq. 3.6)

    dJ[V] = d/dt J((id + tV)(Ω))|_{t=0}
          = ∫_Ω (f' + f div V) dx + ∫_∂Ω (g' + g div_Γ V) ds,

with ``f'``, ``g'`` the derivatives of the integrands as the points move (the material
derivatives; a finite element function moves with the mesh).  NGSolve's
``SumOfIntegrals.DiffShape(ψ)`` gives this linear form in the test function ``ψ`` of ``X``;
assembled, ``dJ[V] = dJ · V`` on the coefficients.  The derivative is of the *discrete*
functional: it equals a central difference of ``J`` under ``SetDeformation(±hV)`` up to
O(h²) when the same quadrature serves both (:func:`shape_dx`, :func:`shape_ds`: every
integral here carries ``bonus_intorder = 2``, without which the two differ by ~6e-5, see the
NGSolve notes).

Dofs on held regions (a clamp, a pressure inlet) are zeroed in every gradient: the shape may
not move there.  ``hold`` is a tuple of region names (every component held) or a
:class:`~pacto_ng.physics.mechanics.Supports` (``clamp`` every component, ``fix_x``/``fix_y``/
``fix_z`` one: a symmetry line slides along itself).
"""
from __future__ import annotations

import numpy as np
from ngsolve import CF, VOL, GridFunction, Integrate, LinearForm, VectorH1, ds, dx

from ..physics.mechanics import Supports
from ..physics.spaces import dirichlet_options

#: extra quadrature order of every form whose shape derivative is taken (the NGSolve notes:
#: the t-derivative of an integrand has a higher degree than the integrand)
BONUS_INTORDER = 2


def shape_dx(rules=None):
    """The volume measure of every shape-differentiated integral: ``dx`` with
    :data:`BONUS_INTORDER`, or with the quadrature ``rules`` (per element type) where the
    forms' own orders differ (the same rules then serve the state and its shape
    derivative)."""
    return dx(bonus_intorder=BONUS_INTORDER) if rules is None else dx(intrules=rules)


def shape_ds(region: str):
    """The measure on the boundary ``region`` of every shape-differentiated integral: ``ds``
    with :data:`BONUS_INTORDER`."""
    return ds(region, bonus_intorder=BONUS_INTORDER)


class ShapeSpace:
    """The deformation ``d`` of a part's mesh (see the module).

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The part's reference mesh Ω0 (2D or 3D).
    order : int
        Order of the VectorH1 space ``X`` of ``d`` and of the gradients.
    hold : tuple of str or Supports
        The regions that may not move (every component for a tuple of names).
    near : tuple of (point, radius)
        Balls that may not move: every element reaching into one is held (e.g. the support
        of an output spring spread about its port, :meth:`~pacto_ng.physics.loads.Spring.
        support`).

    Attributes: ``mesh``, ``space`` (``X``), ``deformation`` (the GridFunction of ``d``),
    ``held`` (numpy mask of the held dofs), ``ndof``.
    """

    def __init__(self, mesh, *, order: int = 1, hold: tuple[str, ...] | Supports = (),
                 near: tuple = ()):
        supports = hold if isinstance(hold, Supports) else Supports(clamp=tuple(hold))
        self.mesh = mesh
        self.space = VectorH1(mesh, order=int(order), **dirichlet_options(mesh, supports))
        self.held = ~np.array(list(self.space.FreeDofs()), dtype=bool)
        for point, radius in near:
            self.held[self._dofs_near(np.asarray(point, dtype=float), float(radius))] = True
        self.deformation = GridFunction(self.space)
        self.ndof = self.space.ndof

    def _dofs_near(self, point, radius: float) -> list[int]:
        """The dofs of every element that reaches into the ball of ``radius`` about
        ``point``: one with a vertex within ``radius`` plus its diameter (with a tenth more
        for a curved element)."""
        xyz = np.array([v.point for v in self.mesh.vertices], dtype=float)
        dofs = []
        for el in self.mesh.Elements(VOL):
            corners = xyz[[v.nr for v in el.vertices]]
            size = max(np.linalg.norm(a - b) for a in corners for b in corners)
            if np.min(np.linalg.norm(corners - point, axis=1)) <= radius + 1.1 * size:
                dofs.extend(self.space.GetDofNrs(el))
        return dofs

    def set(self, values) -> None:
        """Move the mesh to ``Ω = (id + d)(Ω0)``, ``d`` given by its coefficients ``values``."""
        values = np.asarray(values, dtype=float)
        if values.shape != (self.ndof,):
            raise ValueError(f"shape: {values.shape} coefficients for a space of {self.ndof}")
        self.deformation.vec.FV().NumPy()[:] = values
        self.mesh.SetDeformation(self.deformation)

    def moved_points(self) -> np.ndarray:
        """The mesh's vertices at their moved positions ``x0 + d(x0)``, (nv, dim).  Of an
        order-1 space the vertex displacements are the coefficients (component ``k`` of
        vertex ``i`` at ``k·nv + i``: exact); otherwise ``d`` is read at the reference
        vertices with the deformation unset (a finite element function moves with the mesh:
        the NGSolve notes, "Shape derivatives"; a point search, exact to ~1e-8 relative)."""
        ref = np.array([v.point for v in self.mesh.vertices], dtype=float)
        if self.vertex_dofs:
            return self.points_at(self.deformation.vec.FV().NumPy())
        self.mesh.UnsetDeformation()
        try:
            where = self.mesh(*(ref[:, k] for k in range(ref.shape[1])))
            motion = np.asarray(self.deformation(where), dtype=float).reshape(ref.shape)
        finally:
            self.mesh.SetDeformation(self.deformation)
        return ref + motion

    @property
    def vertex_dofs(self) -> bool:
        """Whether the coefficients are the vertex displacements (an order-1 space)."""
        return self.space.globalorder == 1 and self.ndof == self.mesh.dim * self.mesh.nv

    def points_at(self, values) -> np.ndarray:
        """The vertices moved by the coefficients ``values`` of an order-1 space (component
        ``k`` of vertex ``i`` at ``k·nv + i``), (nv, dim); the mesh is not moved."""
        if not self.vertex_dofs:
            raise ValueError("points_at: the coefficients are vertex displacements only in "
                             "an order-1 space")
        ref = np.array([v.point for v in self.mesh.vertices], dtype=float)
        return ref + np.asarray(values, dtype=float).reshape(self.mesh.dim, -1).T

    def direction(self, field, on: str | None = None) -> np.ndarray:
        """The coefficients of a vector CoefficientFunction ``field`` set into ``X`` on the
        reference mesh (only the dofs of the boundary ``on``, if given, the rest zero), held
        dofs zeroed: a direction ``V`` for a derivative or a check."""
        gf = GridFunction(self.space)
        self.mesh.UnsetDeformation()
        if on is None:
            gf.Set(field)
        else:
            gf.Set(field, definedon=self.mesh.Boundaries(on))
        self.mesh.SetDeformation(self.deformation)
        out = gf.vec.FV().NumPy().copy()
        out[self.held] = 0.0
        return out

    def derivative(self, integrals) -> np.ndarray:
        """``dJ`` of ``J = integrals`` (a SumOfIntegrals of the current shape's fields and
        coefficients) as the vector on ``X`` with ``dJ[V] = dJ · V``, held dofs zeroed."""
        lf = LinearForm(self.space)
        lf += integrals.DiffShape(self.space.TestFunction()).Compile()
        lf.Assemble()
        out = lf.vec.FV().NumPy().copy()
        out[self.held] = 0.0
        return out


def volume_integrals(thickness: float = 1.0):
    """The part's volume ``t ∫_Ω 1 dx`` (``t`` the thickness of a 2D part, 1 in 3D) as an
    integral, whose shape derivative is ``t ∫_Ω div V dx`` (the module's formula, ``f = 1``)."""
    return (float(thickness) * CF(1.0)) * shape_dx()


def volume(mesh, thickness: float = 1.0) -> float:
    """The volume ``t |Ω|`` of the current shape (:func:`volume_integrals`)."""
    return float(Integrate(volume_integrals(thickness), mesh))
