"""3D resources (pacto_ng/resources.py): Netgen's tetrahedra estimated from the volume on
shapes the fit did not use, dofs counted exactly for grids and meshes, and a 3D mesh that
would not fit this machine refused in one line before anything is meshed."""
import time

import numpy as np
import pytest

from pacto_ng import resources
from pacto_ng.box import Block, Box, Patch, netgen_box_mesh, structured_box
from pacto_ng.meshing import mesh_geometry
from pacto_ng.params import InputError
from pacto_ng.resource_probes import probe_shape


@pytest.mark.parametrize("name, maxh", [("lbracket", 0.1), ("chamber", 0.005), ("sphere", 0.2)])
def test_tetrahedra_estimate_on_shapes_not_fitted(name, maxh):
    """The docstring's 0.59-1.53 of Netgen's count on these shapes (the fit: cube, slab, bar,
    holed box)."""
    from netgen import occ

    shape = probe_shape(name)
    actual = occ.OCCGeometry(shape).GenerateMesh(maxh=maxh).ne
    ratio = resources.shape_elements(shape, maxh) / actual
    assert 0.5 < ratio < 1.7, (name, maxh, ratio)


def test_a_box_estimate_against_netgen():
    box = Box(0.04, 0.02, 0.01, patches=(Patch("fixed", "xmin"),))
    est = resources.estimate_netgen(resources.netgen_elements(8e-6, 0.002, 3), 1, 3)
    actual = netgen_box_mesh(box, 0.002)
    assert 0.5 < est.elements / actual.ne < 1.7
    # vertices n/5, edges n + vertices: the order-1 and order-2 dofs within 25 %
    from ngsolve import VectorH1

    for k in (1, 2):
        est = resources.estimate_netgen(actual.ne, k, 3)
        assert est.dofs == pytest.approx(VectorH1(actual, order=k).ndof, rel=0.25)


@pytest.mark.parametrize("order", [1, 2, 3])
def test_dofs_are_exact_for_grids_and_meshes(order):
    from ngsolve import VectorH1

    box = Box(1.0, 0.5, 0.5, blocks=(Block("core", "solid", (0.25, 0.0, 0.0),
                                           (0.5, 0.25, 0.25)),))
    hexes = structured_box(box, 6, 3, 2)
    grid = resources.estimate_grid((6, 3, 2), order)
    assert grid.exact and grid.elements == 36 and grid.kind == "hexahedra"
    assert grid.dofs == VectorH1(hexes, order=order).ndof
    tets = netgen_box_mesh(box, 0.2)
    for mesh, kind in ((hexes, "hexahedra"), (tets, "tetrahedra")):
        est = resources.estimate_mesh(mesh, order)
        assert est.kind == kind and est.elements == mesh.ne
        assert est.dofs == VectorH1(mesh, order=order).ndof


def test_3d_memory_is_above_2d_at_the_same_dofs():
    """Fill-in in 3D: the factorisation of the same number of dofs takes more memory."""
    for solver in ("sparsecholesky", "umfpack"):
        m3 = resources.run_memory(1e5, 1, 1e5 / 0.6, 3, solver=solver)
        m2 = resources.run_memory(1e5, 1, 1e5 / 1.0, 2, solver=solver)
        assert m3 > 3 * m2


@pytest.fixture
def no_meshing(monkeypatch):
    from netgen import occ

    import pacto_ng.geometry_kinds as kinds

    def started(*args, **kwargs):
        raise AssertionError("meshing started")

    monkeypatch.setattr(occ, "OCCGeometry", started)
    monkeypatch.setattr(kinds, "netgen_box_mesh", started)
    monkeypatch.setattr(kinds, "structured_box", started)


@pytest.mark.parametrize("geometry, kwargs, words", [
    ("solid", {"maxh": 1e-4}, ("maxh = 0.0001", "tetrahedra", "displacement dofs", "memory",
                               "larger maxh")),
    ("box", {"maxh": 1e-4}, ("maxh = 0.0001", "tetrahedra", "memory")),
    ("box", {"maxh": 0.1, "nelx": 2000, "nely": 1000, "nelz": 1000},
     ("nelx x nely x nelz = 2000 x 1000 x 1000", "hexahedra", "memory",
      "smaller nelx, nely, nelz or order")),
])
def test_a_3d_mesh_too_large_is_refused_before_meshing(geometry, kwargs, words, no_meshing):
    from netgen import occ

    if geometry == "solid":
        geometry = occ.Box((0, 0, 0), (1, 0.5, 0.5))
    else:
        geometry = Box(1.0, 0.5, 0.5)
    t = time.perf_counter()
    with pytest.raises(InputError) as err:
        mesh_geometry(geometry, order=2, **kwargs)
    line = str(err.value)
    assert "\n" not in line and time.perf_counter() - t < 1.0
    for w in words:
        assert w in line, line


def test_the_limit_comes_from_the_memory_fit():
    """A mesh just under and just over a given limit (the check's own ``limit``)."""
    est = resources.estimate_netgen(resources.netgen_elements(1.0, 0.05, 3), 2, 3,
                                    solver="sparsecholesky")
    resources.check(est, "maxh = 0.05", limit=(1.01 * est.memory, "test"))
    with pytest.raises(InputError, match="maxh = 0.05: about .* tetrahedra"):
        resources.check(est, "maxh = 0.05", limit=(0.99 * est.memory, "test"))
    assert np.isfinite(est.memory) and est.memory > 1e8


def test_the_route_is_the_physics_choice():
    """Order 2 above 5·10⁴ dofs: ``solver = auto`` solves iteratively (BDDC), whose memory is
    far below a factorisation's; ``direct`` is estimated as a factorisation."""
    auto = resources.estimate_grid((40, 20, 20), 2, solver="sparsecholesky")
    direct = resources.estimate_grid((40, 20, 20), 2, solver="sparsecholesky",
                                     linear_solver="direct")
    assert resources.route(auto.dofs, 2, 3) == "iterative"
    assert resources.route(auto.dofs, 1, 3) == "direct"  # order 1: BDDC would be direct
    assert direct.memory > 5 * auto.memory
