"""The linear system of a linear, conservative mechanics block whose energy declares itself
quadratic (:class:`~pacto_ng.physics.traits.EnergyTraits`): ``R(u) = K u - s f``.

``K`` is the Hessian of the potential, assembled as a symbolic bilinear form instead of by
``AssembleLinearization`` of the ``Variation`` form (second-order automatic differentiation at
every quadrature point, 3-7x slower).  The integrand is ``(C ∇u) : ∇v`` with the fourth-order
tensor ``C = ∂²(t φ)/∂G²`` obtained from the energy by ``.Diff`` twice, evaluated once per
element (it is constant on each, as declared) and handed to the form as an L2-order-0 field.
Springs enter as ``∂/∂u`` of their energies.  ``f`` (the external load at unit load factor) is
the LinearForm of the loads' work and ``t b·v`` (or ``B p`` of a body coupling).

Because ``t φ(G) = ½ G:C:G`` exactly, the strain energy, its gradient ``K_φ u`` (``K`` minus
the design-independent spring matrix) and the field derivatives ``∫ (∂C/∂ρ ∇u) : ∇w`` follow
from ``C`` too.  With a declared modulus (``φ = E(fields) φ1``, SIMP) ``C = E C1`` per element:
from the second design on ``K`` comes from element matrices computed once
(:class:`~pacto_ng.physics.scatter.ElementMatrices`) and ``E``, ``∂E/∂field`` from the
declared numpy modulus.  On an iterative solver's route the form still assembles ``K`` at the
designs where the solver's preconditioner is set up from it, the element matrices at the
others (:mod:`~pacto_ng.physics.reuse`).

The declarations are verified once at construction, on random values of every field at the
block's quadrature points (``C`` at two different ``G``, ``∂φ/∂G = C G``, ``φ = ½ G:C:G``,
``C`` against its element-wise constant projection; the modulus against the CF): a wrong one
raises :class:`~pacto_ng.physics.traits.DeclarationError`.  Equal to the ``Variation``
tangent, residual and sensitivities to round-off (tests/physics/test_linear_fast.py).
"""
from __future__ import annotations

from contextlib import contextmanager

import numpy as np

from ..parallel import free_norm
from .quadrature import centroid_rules, stiffness_rules
from .scatter import ElementMatrices
from .traits import DeclarationError

#: the element matrices' budget (entries) on an iterative solver's route, where they let its
#: preconditioner be kept across designs (reuse.py): 1.2 GB at 12 bytes each, up to about 5e5
#: dofs of order-2 tetrahedra (cantilever-3d at 228,318 dofs: 45.5 million entries, built in
#: 18.7 s, one thread, two assemblies with BDDC's set-up of 5.3 s each among them)
ITERATIVE_MAX_ENTRIES = 100_000_000


@contextmanager
def fields_restored(mech):
    """Restore the values of every field of ``mech`` on exit (around random states)."""
    saved = [f.gf.vec.FV().NumPy().copy() for f in mech.fields]
    try:
        yield
    finally:
        for f, v in zip(mech.fields, saved):
            f.gf.vec.FV().NumPy()[:] = v


def random_fields(mech, rng):
    """Random values for every field of ``mech`` (densities in [0.2, 1], others in [-1, 1])."""
    for f in mech.fields:
        lo = 0.2 if f.space is mech.l2 else -1.0
        f.gf.vec.FV().NumPy()[:] = rng.uniform(lo, 1.0, len(f.gf.vec))


#: the most quadrature points at which a quadratic energy's declaration is verified
VERIFY_POINTS = 50_000


def _close(got, ref, tol, floor=1e-300):
    """``max |got - ref| <= tol max |ref|``, and ``got`` finite."""
    got, ref = np.asarray(got), np.asarray(ref)
    if ref.size == 0:  # a rank without elements (pacto_ng.parallel)
        return True
    return bool(np.all(np.isfinite(got))
                and np.max(np.abs(got - ref)) <= tol * max(float(np.max(np.abs(ref))), floor))


class LinearSystem:
    """``K`` and ``f`` of a linear, conservative block with a quadratic energy (see the module).

    Used by :class:`~pacto_ng.physics.mechanics.Mechanics` (its :attr:`linear_system`) and by
    :class:`~pacto_ng.responses.StrainEnergy` (:meth:`energy_gradient`, :meth:`field_form`).
    """

    def __init__(self, mech, coupling=None):
        from ngsolve import CF, L2, BilinearForm, GridFunction, Grad, LinearForm, VOL, dx

        self.mech = mech
        self._Ku, self._Ku_at = None, None  # K u of the last residual and (version, u) of it
        mesh, fes, DX = mech.mesh, mech.fes, mech.DX
        d = self.d = mesh.dim
        dd = d * d
        u, v = fes.TnT()
        self.stale = True
        self.version = 0  # increases with every assembly (a new design)
        # C = ∂²(tφ)/∂G² at two different (constant) G
        Gs = [CF(tuple(0.1 * (k + 1) * (1 + j) for k in range(dd)), dims=(d, d)).MakeVariable()
              for j in range(2)]
        phis = [mech.thickness * mech.energy(G, mech.coeffs) for G in Gs]
        Cs = [phi.Diff(G).Diff(G).Reshape((dd, dd)).Compile() for phi, G in zip(phis, Gs)]
        self.C = Cs[0]
        self._centroids = mesh.MapToAllElements(centroid_rules(), VOL)
        self._verify_quadratic(Cs, phis, Gs)
        self.l2C = L2(mesh, order=0, dim=dd * dd)
        self.gfC = GridFunction(self.l2C)
        # (not compiled: the plain tree assembles faster here, 0.052 against 0.067 s)
        integrand = (self.gfC.Reshape((dd, dd)) * Grad(u).Reshape((dd,))) \
            * Grad(v).Reshape((dd,))
        self.a = BilinearForm(fes, symmetric=True)
        # C is constant on each element (verified above): exact with a rule of lower degree
        self.a += integrand * dx(intrules=stiffness_rules(mech.order, mech.rules))
        self._volume = list(self.a.integrators)  # the springs below are not element-wise
        self.springs = None
        if mech.springs:
            self.springs = BilinearForm(fes, symmetric=True)
            for sp in mech.springs:
                self.a += sp.energy(mesh, u).Diff(u, v)
                self.springs += sp.energy(mesh, u).Diff(u, v)
            self.springs.Assemble()  # design-independent
        self.f = LinearForm(fes)
        terms = [ld.work(mesh, v) for ld in mech.loads]
        # a body load linear in one field (the Darcy pressure): B p, with the point loads
        # (design independent) assembled once
        self._coupling = coupling
        if mech.body is not None and coupling is None:
            terms.append((mech.thickness * mech.body(v, mech.coeffs)).Compile() * DX)
        for t in terms:
            self.f += t
        self.has_load = bool(terms) or coupling is not None
        self._fpoints = None
        if coupling is not None:
            self._fpoints = self.f.vec.CreateVector()
            self._fpoints[:] = 0.0
            if terms:
                self.f.Assemble()
                self._fpoints.data = self.f.vec
        # ∂C/∂field for the element-wise fields the energy reads, evaluated on demand
        self._dC, self._dC_version = {}, -1
        for f in mech.fields:
            if f.space is mech.l2 and mech.energy_fields[f.name]:
                self._dC[f.name] = (self.C.Diff(f.gf, mech.one).Compile(), GridFunction(self.l2C))
        self.field_names = tuple(self._dC)
        # a declared modulus: C = (E / E1) C1 per element; the element matrices from the second
        # design on (not for the first, so that a single analysis does not pay for them), or
        # from the first after expect_many_designs
        self.scatter = None
        #: K's LinearSolver (set by its owner): on the iterative route it says at which designs
        #: K is assembled by its form, whose assembly sets up its preconditioner, and not from
        #: the element matrices (LinearSolver.rebuild_due; reuse.py)
        self.solver = None
        self._scatter_built = False
        self._many_designs = False
        self._modulus = None
        self._g = self._dg = None
        modulus = mech.energy_traits.modulus
        if modulus is not None:
            self._modulus, self._C1 = self._verify_modulus(modulus)

    # -- verification of the declaration ------------------------------------------------------
    def _verify_quadratic(self, Cs, phis, Gs, tol=1e-12):
        """Raise :class:`DeclarationError` unless, for random field values (restored), ``C`` is
        the same at two different ``G``, ``∂φ/∂G = C G``, ``φ = ½ G:C:G`` and ``C`` equals its
        element-wise constant projection, at the block's quadrature points: every one on a
        mesh of up to :data:`VERIFY_POINTS` of them, else that many drawn at random (C holds
        d⁴ values per point: at every point of 308 738 tetrahedra of order 2 the check alone
        took 15.6 GB, three times the run's solve)."""
        from ngsolve import L2, VOL, GridFunction

        mech = self.mech
        rng = np.random.default_rng(12345)
        with fields_restored(mech):
            for f in mech.fields:
                f.gf.vec.FV().NumPy()[:] = rng.uniform(0.2, 1.0, len(f.gf.vec))
            pts = mech.mesh.MapToAllElements(mech.rules, VOL)
            if len(pts) > VERIFY_POINTS:
                pts = pts[np.sort(rng.choice(len(pts), VERIFY_POINTS, replace=False))]
            c0, c1 = (np.asarray(C(pts)) for C in Cs)
            n = self.d * self.d
            G = Gs[0]
            gv = np.asarray(G(pts)).reshape(len(c0), n)
            CG = np.einsum("pij,pj->pi", c0.reshape(len(c0), n, n), gv)
            dphi = np.asarray(phis[0].Diff(G)(pts)).reshape(gv.shape)
            phi = np.asarray(phis[0](pts)).ravel()
            g = GridFunction(L2(mech.mesh, order=0, dim=c0.shape[1]))
            g.Set(Cs[0])
            proj = np.asarray(g(pts))
        checks = (
            (_close(c1, c0, tol), "its Hessian ∂²φ/∂G² changes with G"),
            (_close(dphi, CG, tol), "∂φ/∂G is not C G (a linear term in G)"),
            (_close(phi, 0.5 * np.einsum("pi,pi->p", gv, CG), tol),
             "φ is not ½ G:C:G (a term constant in G)"),
            (_close(proj, c0, tol), "C is not constant on each element (does it depend on the "
                                    "position or on a field that is not element-wise?)"),
        )
        for ok, why in checks:
            if not ok:
                raise DeclarationError(f"the energy declares itself quadratic, but {why}; "
                                       f"declare quadratic=False (the general route)")

    def _field_values(self, names):
        return {n: self.mech.coeffs[n].vec.FV().NumPy() for n in names}

    def _verify_modulus(self, modulus, tol=1e-12):
        """``((modulus, E at state 1), C at state 1)`` after checking, on two random states of
        the fields (restored), that ``C(state 2) = g C(state 1)`` per element with ``g`` the
        declared modulus's ``E(state 2) / E(state 1)``, and that ``g`` and ``∂g/∂field`` equal
        the energy's at a fixed ``G*`` (``φ(G*; state 2) / φ(G*; state 1)`` and its
        derivatives); :class:`DeclarationError` otherwise.  Per design only ``E`` and
        ``∂E/∂field`` are evaluated, in numpy (measured at 120 x 80, one thread: 108 against
        118 ms per analysis for the CF at every element centre)."""
        from ngsolve import CF

        mech, d, ne = self.mech, self.d, self.mech.mesh.ne
        names = self.field_names
        G = CF(tuple(0.1 * (k + 1) for k in range(d * d)), dims=(d, d))
        phi = mech.thickness * mech.energy(G, mech.coeffs)
        gcf = CF((phi,) + tuple(phi.Diff(mech.coeffs[n], mech.one) for n in names)).Compile()
        rng = np.random.default_rng(1357)
        states = []
        with fields_restored(mech):
            for _ in range(2):
                random_fields(mech, rng)
                states.append((np.asarray(self.C(self._centroids)).reshape(ne, self.C.dim),
                               np.asarray(gcf(self._centroids)).reshape(ne, gcf.dim),
                               {n: v.copy() for n, v in self._field_values(names).items()}))
        (c1, v1, f1), (c2, v2, f2) = states
        E1 = np.asarray(modulus(f1)[0], dtype=float).copy()
        gn, dgn = self._relative_modulus(modulus, f2, E1, names)
        phi1 = v1[:, 0]
        checks = (
            (np.all(np.isfinite(c1)) and np.all(phi1 > 0) and np.all(E1 > 0),
             "φ(G*) or E is not positive"),
            (_close(c2, gn[:, None] * c1, tol), "C is not E(fields) C1 per element"),
            (_close(gn, v2[:, 0] / phi1, tol), "E(state 2) / E(state 1) is not the energy's"),
        ) + tuple((_close(dgn[:, j], v2[:, 1 + j] / phi1, tol),
                   f"∂E/∂{n} is not the energy's") for j, n in enumerate(names))
        for ok, why in checks:
            if not ok:
                raise DeclarationError(f"the energy's declared modulus is wrong: {why} (on "
                                       f"random fields); fix it or declare modulus=None")
        return (modulus, E1), c1

    @staticmethod
    def _relative_modulus(modulus, values, E1, names):
        """``(g, ∂g/∂field as columns in the order of names)`` with ``g = E / E1``."""
        E, dE = modulus(values)
        E = np.asarray(E, dtype=float)
        dg = np.column_stack([np.asarray(dE.get(n, np.zeros_like(E))) for n in names])
        return E / E1, dg / E1[:, None]

    # -- assembly ---------------------------------------------------------------------------
    @property
    def route(self) -> str:
        """``"element_matrices"`` once ``K`` comes from them, else ``"hessian"``."""
        return "element_matrices" if self.scatter is not None else "hessian"

    @property
    def uses_modulus(self) -> bool:
        """Whether ``E`` comes from the energy's declared numpy modulus."""
        return self._modulus is not None

    @property
    def _numpy_modulus(self) -> bool:
        """Whether ``C = g C1`` (and ``∂C``) come from the declared modulus in numpy: with the
        element matrices, and on an iterative solver's route (its form's assembly then needs
        no evaluation of C's CF at the centroids)."""
        return self._modulus is not None and (self.scatter is not None or self._iterative)

    @property
    def _iterative(self) -> bool:
        return self.solver is not None and not self.solver.direct

    def expect_many_designs(self):
        """Say that many designs follow (an optimisation): the element matrices are built at
        the next assembly, not at the second design.  Every design of a run then takes one
        route, whichever design its process starts at (a resumed run repeats the uninterrupted
        one bit for bit)."""
        self._many_designs = True

    def _build_scatter(self):
        """Build the element matrices (once; above their memory budget the assembly stays
        symbolic)."""
        self._scatter_built = True
        gfc = self.gfC.vec.FV().NumPy()
        c1 = self._C1
        setc = lambda cs: gfc.__setitem__(slice(None), (cs[0][:, None] * c1).ravel())
        budget = {"max_entries": ITERATIVE_MAX_ENTRIES} if self._iterative else {}
        self.scatter = ElementMatrices.build(self.a, self.mech.fes, setc, 1,
                                             volume=self._volume, **budget)

    def assemble(self):
        """Assemble ``K`` and ``f`` for the current fields (once per design)."""
        if not self.stale:
            return
        built = False
        if (self._modulus is not None and not self._scatter_built
                and (self.version >= 1 or self._many_designs)):
            self._build_scatter()  # a second design: from now on worth the element matrices
            built = True  # (its checks assembled the form with other coefficients)
        if self._numpy_modulus:
            modulus, E1 = self._modulus
            self._g, self._dg = self._relative_modulus(
                modulus, self._field_values(self.field_names), E1, self.field_names)
            self.gfC.vec.FV().NumPy()[:] = (self._g[:, None] * self._C1).ravel()
        else:
            self.gfC.vec.FV().NumPy()[:] = np.asarray(self.C(self._centroids)).ravel()
        if self.scatter is None or self._iterative and (built or self.solver.rebuild_due):
            self.assemble_form()
            if self.solver is not None:
                self.solver.rebuilt()
        else:
            self.scatter.assemble([self._g])
        if self._coupling is not None:
            self.f.vec.data = self._fpoints + self._coupling.load()
        elif self.has_load:
            self.f.Assemble()
        else:
            self.f.vec[:] = 0.0
        self.stale = False
        self.version += 1

    def assemble_form(self):
        """``K`` of the current design assembled by its form, which sets up an iterative
        solver's preconditioner from it."""
        self.a.Assemble()

    def residual(self, vec, out, load):
        self.assemble()
        # element by element (Apply), not K u: the product with the assembled K cancels large
        # terms where the structure moves rigidly; from the element gradients the residual is
        # exact to round-off of ∇u (measured on a PneuNet design: K u gave Newton a residual
        # floor whose noise reached SE at 4e-11 and the finite differences at 1e-5)
        self.a.Apply(vec, out)
        # K u of this state, for energy_gradient (Newton's last residual is at the solution)
        if self._Ku is None:
            self._Ku = out.CreateVector()
        self._Ku.data = out
        self._Ku_at = (self.version, vec.FV().NumPy().copy())
        out.data -= load * self.f.vec

    def load_norm(self):
        self.assemble()
        return free_norm(self.f.vec, self.mech.free)

    # -- strain energy and its derivatives from C ----------------------------------------------
    def energy_gradient(self, vec, out):
        """``∂/∂u t∫φ(∇u) = K u - K_springs u`` (element by element, as :meth:`residual`)."""
        self.assemble()
        at = self._Ku_at
        if at is not None and at[0] == self.version and np.array_equal(at[1], vec.FV().NumPy()):
            out.data = self._Ku  # the residual's K u at this state (the same Apply)
        else:
            self.a.Apply(vec, out)
        if self.springs is not None:
            out.data -= self.springs.mat * vec

    def field_form(self, name, gu, gw, factor=1.0, extra=None):
        """``factor ∫ (∂C/∂field ∇gu) : ∇gw q (+ extra q)`` on the element space, used like a
        LinearForm (``Assemble()``, then ``vec``); call :meth:`prepare_fields` before
        assembling it."""
        from ngsolve import Grad, LinearForm

        m, dd = self.mech, self.d * self.d
        dC = self._dC[name][1].Reshape((dd, dd))
        cf = factor * ((dC * Grad(gu).Reshape((dd,))) * Grad(gw).Reshape((dd,)))
        q = m.l2.TestFunction()
        lf = LinearForm(m.l2)
        lf += cf * q * m.DX
        if self._modulus is not None:
            body = None
            if extra is not None:
                body = LinearForm(m.l2)
                body += extra.Compile() * q * m.DX
            return _FieldForm(self, name, gu, gw, factor, lf, body)
        if extra is not None:
            lf += extra.Compile() * q * m.DX
        return lf

    def prepare_fields(self):
        """Evaluate ``∂C/∂field`` per element for the current design (once per design)."""
        self.assemble()
        if self._dC_version == self.version:
            return
        if self.scatter is not None:  # ∂g/∂field came with g (assemble)
            self._dC_version = self.version
            return
        if self._numpy_modulus:  # ∂C = ∂g C1, ∂g from assemble
            for j, (_, gf) in enumerate(self._dC.values()):
                gf.vec.FV().NumPy()[:] = (self._dg[:, j][:, None] * self._C1).ravel()
        else:
            for cf, gf in self._dC.values():
                gf.vec.FV().NumPy()[:] = np.asarray(cf(self._centroids)).ravel()
        self._dC_version = self.version


class _FieldForm:
    """``factor ∫ (∂C/∂field ∇gu) : ∇gw q dΩ`` per element: with the element matrices of
    :class:`~pacto_ng.physics.scatter.ElementMatrices` (once built) as
    ``factor ∂g/∂field · gw_eᵀ K1_e gu_e``, before that the LinearForm ``lf``; plus the
    LinearForm ``extra`` (a body load's ``∂(b·λ)/∂field``) when given.  Used like a
    LinearForm: ``Assemble()``, then ``vec``."""

    def __init__(self, lin, name, gu, gw, factor, lf, extra=None):
        self.lin, self.j = lin, lin.field_names.index(name)
        self.gu, self.gw, self.factor = gu, gw, factor
        self.lf, self.extra = lf, extra
        self._vec = lin.mech.one.vec.CreateVector()
        self.vec = self._vec

    def Assemble(self):
        lin = self.lin
        if lin.scatter is None:
            self.lf.Assemble()
            self._vec.data = self.lf.vec
        else:
            q = lin.scatter.quadratic(self.gw.vec.FV().NumPy(), self.gu.vec.FV().NumPy())[0]
            self._vec.FV().NumPy()[:] = self.factor * lin._dg[:, self.j] * q
        if self.extra is not None:  # a design-dependent body load's term
            self.extra.Assemble()
            self._vec.data += self.extra.vec
