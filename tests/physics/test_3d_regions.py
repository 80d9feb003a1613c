"""Guard points, the lowest det F, loads, ports and supports, and auto's strain measure on 3D
meshes (Netgen tetrahedra, structured hexahedra).

References are independent of the code under test: fields that the elements represent exactly
(affine, or trilinear on hexahedra) and their det F, means and strains written out by hand.
"""
from __future__ import annotations

import numpy as np
import pytest

from pacto_ng.physics.materials import linear_energy


def named_box():
    """The unit cube as Netgen tetrahedra with a named face, edge and vertex."""
    from netgen.occ import X, Y, Z, Box, OCCGeometry
    from ngsolve import Mesh

    box = Box((0, 0, 0), (1, 1, 1))
    box.faces.Min(X).name = "clamp"
    box.faces.Max(X).name = "end"
    box.edges.Max(X + Y).name = "ridge"  # x = 1, y = 1, z in [0, 1]
    box.vertices.Max(X + Y + Z).name = "tip"  # (1, 1, 1)
    return Mesh(OCCGeometry(box, dim=3).GenerateMesh(maxh=0.5))


def test_lowest_jacobian_on_hexahedra():
    """u = α x y z e_x on Q1 hexahedra (trilinear: exact), ``det F = 1 + α y z``, lowest on the
    edge y = z = 1: ``1 + α`` at its vertices, and ``1 + α g²`` at the quadrature points, with
    ``g = 1 - h (1 - 1/√3)/2`` the outer Gauss coordinate of the last element row (h = 1/n)."""
    from ngsolve import CF, x, y, z
    from ngsolve.meshes import MakeStructured3DMesh

    from pacto_ng.physics.mechanics import Mechanics, Supports

    n, alpha = 3, -0.6
    mesh = MakeStructured3DMesh(hexes=True, nx=n, ny=n, nz=n)
    mech = Mechanics(mesh, energy=lambda G, c: linear_energy(G, 1.0, 0.3), fields=(),
                     supports=Supports(clamp=("back",)))
    mech.gfu.Set(CF((alpha * x * y * z, 0, 0)))
    g = 1 - (1 - 1 / np.sqrt(3)) / (2 * n)
    low = mech.lowest_jacobian("quadrature")
    assert low["point"] == "quadrature point" and abs(low["J"] - (1 + alpha * g * g)) < 1e-12
    low = mech.lowest_jacobian("corners")
    assert low["point"] == "vertex" and abs(low["J"] - (1 + alpha)) < 1e-12


def test_lowest_jacobian_on_tetrahedra():
    """An affine u = (F - I) X: det F everywhere, found at a quadrature point or (corners) at
    the first corner point, a vertex."""
    from ngsolve import CF, x, y, z

    from pacto_ng.physics.mechanics import Mechanics, Supports

    F = np.array([[0.9, 0.2, 0.0], [0.1, 1.1, -0.1], [0.0, 0.3, 0.8]])
    mesh = named_box()
    mech = Mechanics(mesh, energy=lambda G, c: linear_energy(G, 1.0, 0.3), fields=(),
                     supports=Supports(clamp=("clamp",)))
    A = F - np.eye(3)
    mech.gfu.Set(CF(tuple(A[i, 0] * x + A[i, 1] * y + A[i, 2] * z for i in range(3))))
    for points, kind in (("quadrature", "quadrature point"), ("corners", "vertex")):
        low = mech.lowest_jacobian(points)
        assert low["point"] == kind and abs(low["J"] - np.linalg.det(F)) < 1e-12


def test_loads_and_supports_on_named_faces_edges_and_points():
    """A force on a face, an edge and a point does the work ``F·ū`` with ``ū`` the mean of u over
    the region: for an affine u, u at the region's centroid.  Supports on an edge and a point fix
    exactly the dofs there (P1: the vertices)."""
    from ngsolve import CF, GridFunction, LinearForm, VectorH1, x, y, z

    from pacto_ng.physics.loads import PointLoad, Port
    from pacto_ng.physics.mechanics import Mechanics, Supports

    mesh = named_box()
    fes = VectorH1(mesh, order=1)
    gu = GridFunction(fes)
    gu.Set(CF((1 + 2 * x - y, 3 * z + x * 0.5, -y + 4 * z)))
    u_at = lambda p: np.array([1 + 2 * p[0] - p[1], 3 * p[2] + 0.5 * p[0], -p[1] + 4 * p[2]])
    force = np.array([2.0, -1.0, 0.5])
    for region, centroid in (("end", (1, 0.5, 0.5)), ("ridge", (1, 1, 0.5)), ("tip", (1, 1, 1))):
        lf = LinearForm(fes)
        lf += PointLoad(region, tuple(force)).work(mesh, fes.TestFunction())
        lf.Assemble()
        assert abs(lf.vec.InnerProduct(gu.vec) - force @ u_at(centroid)) < 1e-12, region
        lf = LinearForm(fes)
        lf += Port(region, (0.0, 0.0, 1.0)).functional(mesh, fes.TestFunction())
        lf.Assemble()
        assert abs(lf.vec.InnerProduct(gu.vec) - u_at(centroid)[2]) < 1e-12, region
    with pytest.raises(ValueError, match="2 components on a 3D mesh"):
        PointLoad("end", (1.0, 0.0)).work(mesh, fes.TestFunction())
    mech = Mechanics(mesh, energy=lambda G, c: linear_energy(G, 1.0, 0.3), fields=(),
                     supports=Supports(clamp=("clamp",), fix_y=("ridge",), fix_z=("tip",)))
    on_ridge = sum(1 for v in mesh.vertices if v.point[0] == 1 and v.point[1] == 1)
    fixed = np.count_nonzero(~mech.free)
    assert fixed == 3 * sum(1 for v in mesh.vertices if v.point[0] == 0) + on_ridge + 1


def test_thickness_must_be_one_in_3d():
    from pacto_ng.physics.mechanics import Mechanics, Supports

    with pytest.raises(ValueError, match="thickness must be 1 on a 3D mesh"):
        Mechanics(named_box(), energy=lambda G, c: linear_energy(G, 1.0, 0.3), fields=(),
                  supports=Supports(clamp=("clamp",)), thickness=1e-3)


def test_material_strain_of_a_homogeneous_stretch():
    """``auto``'s strain measure in 3D: u = (F - I) X on solid material has the Green–Lagrange
    strain ``|½(FᵀF - I)|`` (Frobenius) at every point, so its 99th percentile and its largest
    value are that number."""
    from ngsolve import CF, x, y, z

    from pacto_ng.auto import material_strain
    from pacto_ng.physics.mechanics import Mechanics, Supports

    F = np.array([[1.02, 0.01, 0.0], [0.0, 0.99, 0.015], [0.005, 0.0, 1.01]])
    A = F - np.eye(3)
    mesh = named_box()
    mech = Mechanics(mesh, energy=lambda G, c: linear_energy(G, 1.0, 0.3),
                     supports=Supports(clamp=("clamp",)))
    mech.set_fields(np.ones(mesh.ne))
    mech.gfu.Set(CF(tuple(A[i, 0] * x + A[i, 1] * y + A[i, 2] * z for i in range(3))))
    ref = np.linalg.norm(0.5 * (F.T @ F - np.eye(3)))
    s, largest = material_strain(mech)
    assert abs(s / ref - 1) < 1e-12 and abs(largest / ref - 1) < 1e-12
