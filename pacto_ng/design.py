"""Element-wise design densities (L2 order 0) with passive solid/void regions by name."""
from __future__ import annotations

import numpy as np


class DesignField:
    """Maps the design variables ``x`` (one per *design* element) to element densities.

    Elements whose material is listed in ``solid`` get density 1, those in ``void`` density 0;
    every other element (normally material ``design``) is a design element.  The element order
    is NGSolve's (= ``mesh.ngmesh.Elements2D()`` on a 2D mesh, ``Elements3D()`` on a 3D one);
    ``areas`` are the element areas in 2D and volumes in 3D.

    The block :class:`Embed` puts ``x`` into a full element vector; :class:`FixPassive` resets
    the passive elements after filtering and projection so that they stay exactly 0 or 1.
    """

    def __init__(self, mesh, solid=(), void=()):
        mats = [el.mat for el in mesh.Elements()]
        known = set(mesh.GetMaterials())
        for name in list(solid) + list(void):
            if name not in known:
                raise ValueError(f"passive region '{name}' is not a material of the mesh "
                                 f"(materials: {sorted(known)})")
        self.mesh = mesh
        self.ne = mesh.ne
        self.solid = np.array([m in solid for m in mats], dtype=bool)
        self.void = np.array([m in void for m in mats], dtype=bool)
        self.design = ~(self.solid | self.void)
        self.design_index = np.flatnonzero(self.design)
        self.n = int(self.design.sum())
        from ngsolve import Integrate
        self.areas = np.array(Integrate(1.0, mesh, element_wise=True))

    def full(self, x: np.ndarray) -> np.ndarray:
        rho = np.where(self.solid, 1.0, 0.0)
        rho[self.design_index] = x
        return rho

    def centroids(self) -> np.ndarray:
        pts = np.array([v.point for v in self.mesh.vertices])
        return np.array([pts[[v.nr for v in el.vertices]].mean(axis=0) for el in self.mesh.Elements()])


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
