"""topress-3d against an independent numpy transcription of TOPress3D.m's analysis
(tests/topress3d_reference.py), node for node on a 6 x 4 x 3 grid of unit cubes: the pressure
field, the load vector F = -T p, the displacements, the compliance and its gradient at a random
density field, and the cone filter.

The problem is built from the case's geometry, set-up and chain (``mesh_geometry`` of its Box
with nelx, nely, nelz, then ``Builder`` and the case's chain), the steps of
``pacto_ng.case.build_problem``."""
import numpy as np
import pytest
from ngsolve import VERTEX, NodeId

import topress3d_reference as ref
from pacto_ng import Builder, get_case, mesh_geometry

NELX, NELY, NELZ = 6, 4, 3


#: the code's own optimisation settings: no projection, the penalty at its final value (the
#: case's defaults add both continuations, so that its part is crisp)
CODE = dict(beta=0.0, beta_max=0.0, penal_start=0.0)


def build(**values):
    case = get_case("topress-3d")
    params = case.resolve(case.defaults.replace(nelx=NELX, nely=NELY, nelz=NELZ,
                                                **{**CODE, **values}))
    meshed = mesh_geometry(case.make_geometry(params), maxh=params.maxh, nelx=params.nelx,
                           nely=params.nely, nelz=params.nelz, order=params.order)
    return case.make_problem(Builder(case, params, meshed, case.make_setup(params)))


def code_numbering(mesh):
    """The code's element of each NGSolve element and its node of each mesh vertex, from the
    coordinates (x = ix, y = nely - jy, z = kz)."""
    pts = np.array([mesh[v].point for v in mesh.vertices])
    cen = np.array([pts[[v.nr for v in el.vertices]].mean(axis=0) for el in mesh.Elements()])
    ix, y, kz = (np.floor(cen[:, a]).astype(int) for a in range(3))
    elem = (NELY - 1 - y) + NELY * kz + NELY * NELZ * ix
    ix, y, kz = (np.rint(pts[:, a]).astype(int) for a in range(3))
    node = (NELY - y) + (NELY + 1) * kz + (NELY + 1) * (NELZ + 1) * ix
    return elem, node


def vertex_dofs(fes, nv):
    return np.array([fes.GetDofNrs(NodeId(VERTEX, v)) for v in range(nv)])


def rel(a, b):
    return np.max(np.abs(np.asarray(a) - np.asarray(b))) / np.max(np.abs(b))


@pytest.fixture(scope="module")
def rho():
    """A random ρ̄ in [0.05, 0.95] in the code's element order: it crosses ηf = 0.2, so the
    pressure front runs through the domain."""
    return np.random.default_rng(7).uniform(0.05, 0.95, NELX * NELY * NELZ)


def test_analysis_and_gradient_match_the_codes(rho, one_thread):
    prob = build(filter="none")  # ρ̄ = x: no filter, no projection
    mesh = prob.mesh
    elem, node = code_numbering(mesh)
    assert sorted(elem) == list(range(NELX * NELY * NELZ))
    f0, f, df0, df = prob.evaluate(rho[elem])
    r = ref.analyse(rho, NELX, NELY, NELZ)
    g = r["grid"]
    # the code's node sets: 2 (nelx + nely) clamped rim nodes, all three components
    assert (~prob.mech.free).sum() == 3 * len(g.rim) == 6 * (NELX + NELY)
    pd = vertex_dofs(prob.pressure_block.fes, mesh.nv)[:, 0]
    p = prob.pressure_block.gfp.vec.FV().NumPy()[pd]
    assert rel(p, r["p"][node]) < 1e-10
    ud = vertex_dofs(prob.mech.fes, mesh.nv)
    u = prob.mech.gfu.vec.FV().NumPy()[ud]
    F = prob.mech.linear_system.f.vec.FV().NumPy()[ud]  # the load vector at load factor 1
    assert rel(F, r["F"].reshape(-1, 3)[node]) < 1e-10
    assert rel(u, r["U"].reshape(-1, 3)[node]) < 1e-10
    assert abs(f0 - r["compliance"]) / r["compliance"] < 1e-10
    assert abs(f[0] - (r["volume"] / prob.params.volfrac - 1)) < 1e-12
    # the gradient (stiffness and load terms) against the code's adjoint sensitivities
    assert rel(df0, r["sens"][elem]) < 1e-9
    print(f"topress-3d against the transcription: p {rel(p, r['p'][node]):.1e}, F "
          f"{rel(F, r['F'].reshape(-1, 3)[node]):.1e}, u {rel(u, r['U'].reshape(-1, 3)[node]):.1e},"
          f" C {abs(f0 - r['compliance']) / r['compliance']:.1e}, dC {rel(df0, r['sens'][elem]):.1e}")


def test_the_references_sensitivities_are_its_derivative(rho):
    """The transcription's adjoint sensitivities against its own central differences."""
    r = ref.analyse(rho, NELX, NELY, NELZ)
    h = 1e-6
    for e in (0, 17, 40, 71):
        xp, xm = rho.copy(), rho.copy()
        xp[e] += h
        xm[e] -= h
        fd = (ref.analyse(xp, NELX, NELY, NELZ)["compliance"]
              - ref.analyse(xm, NELX, NELY, NELZ)["compliance"]) / (2 * h)
        assert abs(fd - r["sens"][e]) < 1e-6 * abs(fd)


@pytest.mark.parametrize("radius", [2.4, 3.0 ** 0.5])
def test_cone_filter_is_the_codes(rho, radius, one_thread):
    """The case's cone filter measures distances in x, y and z: the code's imfilter / Hs, and
    the compliance and its gradient through it."""
    prob = build(filter="cone", filter_radius=radius)
    elem, _ = code_numbering(prob.mesh)
    f0, f, df0, df = prob.evaluate(rho[elem])
    xphys = ref.density_filter(rho, NELX, NELY, NELZ, radius)
    assert rel(prob.values["rho_bar"], xphys[elem]) < 1e-12
    r = ref.analyse(xphys, NELX, NELY, NELZ)
    assert abs(f0 - r["compliance"]) / r["compliance"] < 1e-10
    dx = ref.filter_sensitivity(r["sens"], NELX, NELY, NELZ, radius)
    assert rel(df0, dx[elem]) < 1e-9
