"""Element-wise design densities (L2 order 0) with passive solid/void regions by name."""
from __future__ import annotations

import numpy as np
from ngsolve import BND, Integrate
from scipy.spatial import cKDTree

from .parallel import all_rows, element_centroids


class DesignField:
    """Maps the design variables ``x`` (one per *design* element) to element densities.

    Elements whose material is listed in ``solid`` get density 1, those in ``void`` density 0;
    every other element (normally material ``design``) is a design element.  ``wall``, a mask
    over the elements (:func:`near_boundary`), adds passive solid elements outside ``void``.
    The element order is NGSolve's (= ``mesh.ngmesh.Elements2D()`` on a 2D mesh,
    ``Elements3D()`` on a 3D one); ``areas`` are the element areas in 2D and volumes in 3D.

    The block :class:`Embed` puts ``x`` into a full element vector; :class:`FixPassive` resets
    the passive elements after filtering and projection so that they stay exactly 0 or 1.
    """

    def __init__(self, mesh, solid=(), void=(), wall=None):
        mats = [el.mat for el in mesh.Elements()]
        known = set(mesh.GetMaterials())
        for name in list(solid) + list(void):
            if name not in known:
                raise ValueError(f"passive region '{name}' is not a material of the mesh "
                                 f"(materials: {sorted(known)})")
        self.mesh = mesh
        self.ne = mesh.ne
        self.void = np.array([m in void for m in mats], dtype=bool)
        self.solid = np.array([m in solid for m in mats], dtype=bool)
        if wall is not None:
            self.solid |= np.asarray(wall, dtype=bool) & ~self.void
        self.design = ~(self.solid | self.void)
        self.design_index = np.flatnonzero(self.design)
        self.n = int(self.design.sum())
        self.areas = np.array(Integrate(1.0, mesh, element_wise=True))

    def full(self, x: np.ndarray) -> np.ndarray:
        rho = np.where(self.solid, 1.0, 0.0)
        rho[self.design_index] = x
        return rho

    def centroids(self) -> np.ndarray:
        return element_centroids(self.mesh)


def near_boundary(mesh, names, distance: float, samples: int = 4) -> np.ndarray:
    """Mask of the elements that touch the boundaries ``names`` or whose centroid lies within
    ``distance`` of them: a layer without gaps, at least one element thick.

    The boundary is sampled at ``samples`` points per edge of each boundary element (in
    barycentric steps), so the distance is exact to a ``1/samples`` of the boundary mesh size."""
    pts = np.array([v.point for v in mesh.vertices], dtype=float).reshape(-1, mesh.dim)
    faces = []
    for el in mesh.Elements(BND):
        if el.mat in names:
            nrs = [v.nr for v in el.vertices]
            faces += [nrs[:3], [nrs[0], nrs[2], nrs[3]]] if len(nrs) == 4 else [nrs]
    k, dim = samples, mesh.dim
    if dim == 2:
        weights = np.array([[i / k, 1 - i / k] for i in range(k + 1)])
    else:
        weights = np.array([[i / k, j / k, 1 - (i + j) / k]
                            for i in range(k + 1) for j in range(k + 1 - i)])
    corners = pts[np.array(faces, dtype=int).reshape(-1, dim)]
    # on a distributed mesh, the boundary's points on every rank
    surface = all_rows(mesh, np.einsum("sc,fcd->fsd", weights, corners).reshape(-1, dim))
    if not len(surface):
        raise ValueError(f"no boundary named {', '.join(names)} to keep a wall around")
    tree = cKDTree(surface)
    dist, _ = tree.query(element_centroids(mesh))
    # the boundary's vertices are among its sample points: at distance 0
    on = tree.query(pts)[0] <= 1e-9 * distance
    touching = np.array([on[[v.nr for v in el.vertices]].any() for el in mesh.Elements()],
                        dtype=bool)
    return (dist < distance) | touching


class Embed:
    """Block ``x -> rho``: design variables into the full element vector (passive set)."""

    def __init__(self, field: DesignField, inputs=("x",), output="rho"):
        self.field, self.inputs, self.output = field, tuple(inputs), output

    def forward(self, x):
        return self.field.full(x)

    def backward(self, g):
        return (np.asarray(g)[self.field.design_index].copy(),)


class FixPassive:
    """Block ``rho -> rho``: passive elements reset to exactly 1 (solid) or 0 (void)."""

    def __init__(self, field: DesignField, inputs=("rho_proj",), output="rho_bar"):
        self.field, self.inputs, self.output = field, tuple(inputs), output

    def forward(self, rho):
        out = np.array(rho, dtype=float)
        out[self.field.solid] = 1.0
        out[self.field.void] = 0.0
        return out

    def backward(self, g):
        g = np.array(g, dtype=float)
        g[~self.field.design] = 0.0
        return (g,)
