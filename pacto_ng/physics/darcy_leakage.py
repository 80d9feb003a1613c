r"""How much a design leaks: :class:`Outflow`, the flow out through the zero-pressure
boundaries (``leak`` in every pressure run's summary.json and in its pressure.png's title; the
``leak_max`` constraint), and the leakage figure of a solved Darcy pressure field (how much of
the inlet pressure reaches solid material away from the pressurised cavity; ``leakage`` in the
summary, read by the benchmark studies' tables of docs/studies.md).
"""
from __future__ import annotations

import numpy as np

from ..parallel import bounding_box, total
from .darcy import DarcyPressure


def leakage(mesh, inlet, rho, p, *, p_in: float, delta_s: float, h: float,
            solid: float = 0.9, void: float = 0.5, skin: float | None = None) -> dict:
    r"""How much pressure reaches solid material away from the pressurised cavity.

    Of a serial ``mesh`` (a distributed run's rank 0 passes the serial mesh it meshed, with
    the fields gathered onto it): ``inlet`` the names of the inlet boundaries, ``rho`` the
    element densities the pressure was solved with, ``p`` the pressures at the vertices,
    ``p_in`` the inlet pressure and ``delta_s`` the Darcy drainage depth.

    Definitions (element densities ``ρ̄``; vertex pressures ``p``):

    * **cavity**: the elements with ``ρ̄ < void`` (0.5) that are connected to the inlet
      boundary through elements with ``ρ̄ < void`` sharing a vertex (an element touching the
      inlet with a vertex starts the search; vertex neighbours because the discrete pressure
      passes through shared vertices);
    * **wet skin**: the elements whose centroid lies within ``skin`` of a vertex of the cavity
      or of the inlet boundary.  Default ``skin = h + 2 max(Δs, h)``: one transition element
      plus the depth at which the solid has brought the pressure down to about 1 %: ``2 Δs``
      for the exact decay ``exp(-|ln r| x / Δs)`` (``r² = 1 %``, docs/theory.md §2), but two
      elements on meshes coarser than the decay length ``Δs / |ln r|``, where the P1 solution
      falls only by a factor of about 0.16–0.2 per element (0.16 at h = 2 Δs, the thesis
      mesh).  In this skin the pressure is expected to drop, not leaked;
    * **outside the cavity**: the elements with ``ρ̄ >= solid`` (0.9) that are not in the skin.

    The leakage is the largest element pressure (the mean of its vertex values) found outside
    the cavity, as a fraction of ``P_in``; 0 if there is no such element.  ``leakage_any`` is
    the same maximum over *every* element that is neither in the cavity nor in the skin (also
    void pockets the pressure reached through a wall, and grey material): the stricter figure.

    Returns a dict: ``leakage``, ``where`` (centroid of that element, or None),
    ``leakage_any``, ``where_any``, ``skin``, ``elements_checked``, ``cavity_elements``.
    """
    from ngsolve import BND
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    rho = np.asarray(rho, dtype=float)
    skin = h + 2.0 * max(delta_s, h) if skin is None else float(skin)
    pts = np.array([v.point for v in mesh.vertices])
    conn = [[v.nr for v in el.vertices] for el in mesh.Elements()]
    rows = np.repeat(np.arange(len(conn)), [len(c) for c in conn])
    cols = np.concatenate(conn)
    inc = csr_matrix((np.ones(rows.size), (rows, cols)), shape=(len(conn), mesh.nv))
    inlet_v = np.zeros(mesh.nv, dtype=bool)
    for el in mesh.Elements(BND):
        if el.mat in inlet:
            inlet_v[[v.nr for v in el.vertices]] = True
    # cavity: components of the low-density elements (vertex adjacency) that touch the inlet
    low = np.flatnonzero(rho < void)
    cavity = np.zeros(len(conn), dtype=bool)
    if low.size:
        sub = inc[low]
        ncomp, label = connected_components(sub @ sub.T, directed=False)
        touching = np.unique(label[np.asarray(sub @ inlet_v.astype(float)).ravel() > 0])
        cavity[low[np.isin(label, touching)]] = True
    wet_v = inlet_v | (np.asarray(inc[cavity].sum(axis=0)).ravel() > 0)
    centroids = np.asarray(inc @ pts) / np.asarray(inc.sum(axis=1))
    dist = cKDTree(pts[wet_v]).query(centroids)[0]
    beyond = ~cavity & (dist > skin)
    outside = beyond & (rho >= solid)
    pe = np.asarray(inc @ np.asarray(p, dtype=float)[:mesh.nv]).ravel() / np.asarray(inc.sum(axis=1)).ravel()
    out = dict(leakage=0.0, where=None, leakage_any=0.0, where_any=None, skin=skin,
               elements_checked=int(outside.sum()), cavity_elements=int(cavity.sum()))
    for key, sel in (("", outside), ("_any", beyond)):
        if sel.any() and p_in != 0:
            k = np.flatnonzero(sel)[np.argmax(pe[sel])]
            out["leakage" + key] = float(max(pe[k], 0.0) / p_in)
            out["where" + key] = [float(c) for c in centroids[k][:2]]
    return out


class Outflow:
    r"""Block ``(ρ̄, p) -> Q / (Kv P_in)``: the Darcy flow out through the zero-pressure
    boundaries, a constraint ``Q / (Kv P_in) <= leak_max`` with :class:`~pacto_ng.builders.Bound`.

    The inlet pressure is prescribed, so a design whose chamber leaks keeps its pressure: in the
    Darcy model a leak costs nothing, and the optimiser may use one (a gap in a wall that turns
    the wall into a flap, or a grey plug that seals the model's chamber but not the
    thresholded part's).  A closed chamber drains its inflow in its walls (the drainage term)
    and almost nothing reaches the outer boundary; a gap lets the flow through the void.  Q is
    the reaction of the zero-pressure condition: with ``z`` the interpolant of 1 on those
    boundaries (0 at every other dof),

        ``Q = -zᵀ(A p - f) = -Σ_e [K_e ∫_e ∇z·∇p dΩ + D_e ∫_e z (p - p_out) dΩ]``,

    the outward flux ``∫ -K ∇p·n`` in the weak form.  It is made dimensionless: per unit
    thickness in 2D (an open channel of height H and length L0 leaks H/L0), per unit length
    ``ℓ`` in 3D, ``ℓ`` the smallest side of the mesh's bounding box (a channel of cross-section
    A leaks A/(L0 ℓ)), so that one limit serves both.  Measured (PneuNet, docs/studies.md):
    1.9e-5 for the closed shell of the linear design, 0.0086 to 0.45 for Wang designs with a gap
    in a chamber wall; in 3D 2.4e-6 for pa-gripper-3d's sealed design, 0.83 and 1.27 for the
    open pneunet-3d and pa-inverter-3d designs.

    Backward: ``∂Q/∂ρ̄_e = -(K'_e ∫_e ∇z·∇p + D'_e ∫_e z (p - p_out))`` and ``∂Q/∂p = -A z``
    on the free dofs (the prescribed pressures do not vary); the ``p`` part flows back through
    the pressure block's adjoint.
    """

    def __init__(self, pressure: DarcyPressure, inputs=None, output: str = "leak"):
        from ngsolve import BND, GridFunction, LinearForm, grad

        self.pressure = pr = pressure
        self.inputs = tuple(inputs) if inputs is not None else (pr.inputs[0], pr.output)
        self.output = output
        if not pr.zero:
            raise ValueError("leak_max: the pressure has no zero-pressure boundary to leak to")
        mesh = pr.mesh
        z = GridFunction(pr.fes)
        z.Set(1.0, BND, definedon=mesh.Boundaries("|".join(pr.zero)))
        self.gfp = GridFunction(pr.fes)
        self.K, self.D = GridFunction(pr.l2), GridFunction(pr.l2)
        q0, q = pr.l2.TestFunction(), pr.fes.TestFunction()
        # per element: ∫ ∇z·∇p and ∫ z (p - p_out)
        self._a = LinearForm(pr.l2)
        self._a += grad(z) * grad(self.gfp) * q0 * pr.DX
        self._b = LinearForm(pr.l2)
        self._b += z * (self.gfp - pr.p_out) * q0 * pr.DX
        # A z (the design's K and D)
        self._az = LinearForm(pr.fes)
        self._az += (self.K * grad(z) * grad(q) + self.D * z * q) * pr.DX
        self._free = np.array(list(pr.fes.FreeDofs()), dtype=bool)
        lo, hi = bounding_box(mesh)
        length = 1.0 if mesh.dim == 2 else float(np.min(hi - lo))
        self._scale = 1.0 / (pr.Kv * pr.p_in * length) if pr.p_in != 0 else 1.0 / length
        self._coefficients = None  # K, D and their derivatives of the last forward's design

    def forward(self, rho, p):
        pr = self.pressure
        if isinstance(p, np.ndarray):
            self.gfp.vec.FV().NumPy()[:] = p
        else:
            self.gfp.vec.data = p
        self._coefficients = pr.coefficients(np.asarray(rho, dtype=float))
        K, D = self._coefficients[:2]
        self._a.Assemble()
        self._b.Assemble()
        a, b = self._a.vec.FV().NumPy(), self._b.vec.FV().NumPy()
        return -self._scale * total(pr.mesh, float(K @ a + D @ b))

    def backward(self, g):
        K, D, dK, dD = self._coefficients
        a, b = self._a.vec.FV().NumPy(), self._b.vec.FV().NumPy()
        drho = -float(g) * self._scale * (dK * a + dD * b)
        self.K.vec.FV().NumPy()[:] = K
        self.D.vec.FV().NumPy()[:] = D
        self._az.Assemble()
        dp = self._az.vec.CreateVector()
        dp.data = (-float(g) * self._scale) * self._az.vec
        dp.FV().NumPy()[~self._free] = 0.0
        return (drho, dp)
