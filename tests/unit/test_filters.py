import numpy as np
import pytest

from pacto_ng.core import check_gradient, taylor_rates
from pacto_ng.design import DesignField, Embed, FixPassive
from pacto_ng.filters import ConeFilter, HeavisideProjection, HelmholtzFilter
from pacto_ng.mesh import Layout, Region, netgen_mesh, structured_mesh


@pytest.fixture(scope="module")
def mesh():
    lay = Layout(1.0, 0.5, regions=(Region("block", "solid", 0.0, 0.0, 0.2, 0.1),))
    return netgen_mesh(lay, 0.06)


def _fd(block, n, seed=0):
    w = np.random.default_rng(seed + 10).normal(size=n)
    fun = lambda x: float(w @ block.forward(x) ** 2)

    def grad(x):
        y = block.forward(x)
        return block.backward(2 * w * y)[0]

    x0 = np.random.default_rng(seed).uniform(0.2, 0.8, n)
    return check_gradient(fun, grad, x0), taylor_rates(fun, grad, x0)


def test_helmholtz_filter_preserves_constants_and_gradient(mesh):
    f = HelmholtzFilter(mesh, 0.15)
    one = f.forward(np.ones(mesh.ne))
    assert np.allclose(one, 1.0, atol=1e-12)
    # it conserves the integral of the density (Neumann boundary)
    x = np.random.default_rng(1).random(mesh.ne)
    assert abs(f.areas @ f.forward(x) - f.areas @ x) < 1e-12 * (f.areas @ x)
    res, rates = _fd(f, mesh.ne)
    assert res.rel_error < 1e-7
    assert np.all(rates > 1.9)


def test_cone_filter_weights_and_gradient():
    lay = Layout(6.0, 3.0)
    m = structured_mesh(lay, 6, 3)
    field = DesignField(m)
    f = ConeFilter(field.centroids(), field.areas, 1.5)
    # the 88-line weights for the element at column 1, row 1: neighbours within 1.5
    x = np.zeros(m.ne)
    x[1 * 6 + 1] = 1.0
    y = f.forward(x)
    w_center, w_side, w_diag = 1.5, 0.5, 1.5 - np.sqrt(2)
    total = w_center + 4 * w_side + 4 * w_diag
    assert abs(y[1 * 6 + 1] - w_center / total) < 1e-14
    assert np.allclose(f.forward(np.ones(m.ne)), 1.0)
    res, rates = _fd(f, m.ne)
    assert res.rel_error < 1e-7


def test_cone_filter_weights_in_3d():
    """Unit cubes: within R = 1.5 of an interior cube lie its 6 face neighbours (weight 0.5),
    12 edge neighbours (1.5 - √2) and none of its corner neighbours (√3 > 1.5) — the weights of
    the 3D 88-line codes; the z distance counts."""
    from ngsolve.meshes import MakeStructured3DMesh

    m = MakeStructured3DMesh(hexes=True, nx=3, ny=3, nz=3,
                             mapping=lambda x, y, z: (3 * x, 3 * y, 3 * z))
    field = DesignField(m)
    c = field.centroids()
    assert c.shape == (27, 3)
    centre = int(np.argmin(np.linalg.norm(c - 1.5, axis=1)))
    f = ConeFilter(c, field.areas, 1.5)
    x = np.zeros(m.ne)
    x[centre] = 1.0
    total = 1.5 + 6 * 0.5 + 12 * (1.5 - np.sqrt(2))
    assert abs(f.forward(x)[centre] - 1.5 / total) < 1e-14
    assert np.allclose(f.forward(np.ones(m.ne)), 1.0)


@pytest.mark.parametrize("beta", [1.0, 8.0, 64.0])
def test_projection_gradient(beta):
    pr = HeavisideProjection(beta, 0.5)
    assert np.allclose(pr.forward(np.array([0.0, 0.5, 1.0])), [0.0, 0.5, 1.0])
    res, _ = _fd(pr, 50)
    assert res.rel_error < 1e-6


def test_passive_regions_fixed(mesh):
    field = DesignField(mesh, solid=("block",))
    assert field.solid.sum() > 0 and field.n == mesh.ne - field.solid.sum()
    x = np.full(field.n, 0.3)
    rho = Embed(field).forward(x)
    assert np.all(rho[field.solid] == 1.0)
    out = FixPassive(field).forward(np.full(mesh.ne, 0.4))
    assert np.all(out[field.solid] == 1.0)
    with pytest.raises(ValueError, match="nope"):
        DesignField(mesh, solid=("nope",))
