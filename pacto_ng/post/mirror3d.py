"""The whole 3D part: the half or quarter a case is solved on, reflected about its symmetry planes.

A case solved on a half or a quarter names its cut faces ``symmetry`` (y = 0) and
``symmetry_z`` (z = D/2; geometries/solids.py).  :func:`symmetry_planes` finds them in the run's
mesh: the boundary faces named ``symmetry`` or ``symmetry_<anything>``, one plane per name, each
perpendicular to x, y or z (the planes of a quarter on different axes), else one InputError.

:func:`mirror_surface` makes the whole part's closed surface: for each plane in turn the
triangles lying on it (the cut face, inside the whole part) are removed, the rest reflected by
VTK's ``vtkReflectionFilter`` (the input kept beside its image, the image's triangles reversed so
that they still face outward) and the points on the plane, now twice, merged (pyvista's
``clean``): one closed surface holding 2^k times the half's volume, no face on a plane.
:func:`mirror_solid` reflects the clipped solid with its fields the same way (the cells'
faces on the plane become inner faces once the points are merged); ``vtkReflectionFilter``'s
``FlipAllInputArrays`` reflects every vector (3 components: the normal component changes sign)
and symmetric tensor (6 components, VTK's order xx, yy, zz, xy, yz, xz: R T Rᵀ) and keeps the
scalars.  The filter writes its points in single precision (6e-8 relative: the binary STL's
own precision; the volume of a mirrored part is 2^k times the half's to about 1e-8).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .part3d import boundary_vertices

#: a point within this fraction of the mesh's diameter of a plane lies on it
PLANE_RTOL = 1e-9
_AXES = "xyz"


@dataclass(frozen=True)
class SymmetryPlane:
    """The plane x[axis] = offset of the boundary faces named ``name``; a point within ``tol``
    (m: :data:`PLANE_RTOL` times the mesh's diameter) of it lies on it."""

    name: str
    axis: int
    offset: float
    tol: float

    def __str__(self) -> str:
        return f"{self.name}: {_AXES[self.axis]} = {self.offset:g} m"


def is_symmetry_name(name: str) -> bool:
    return name == "symmetry" or name.startswith("symmetry_")


def symmetry_planes(mesh, rtol: float = PLANE_RTOL) -> list[SymmetryPlane]:
    """The symmetry planes of a 3D NGSolve mesh (see the module docstring), in the order of
    their names.  InputError (naming ``--mirror``) when a name's faces are not one plane, or
    not perpendicular to an axis, or two names share an axis."""
    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    diam = float(np.ptp(pts, axis=0).max())
    planes = []
    for name in sorted(n for n in set(mesh.GetBoundaries()) if is_symmetry_name(n)):
        v = pts[boundary_vertices(mesh, [name])]
        centre = v.mean(axis=0)
        normal = np.linalg.svd(v - centre, full_matrices=False)[2][-1]
        off = float(np.abs((v - centre) @ normal).max())
        if off > rtol * diam:
            raise InputError(f"--mirror: the symmetry face '{name}' is not planar (its vertices "
                             f"lie up to {off:.3g} m off one plane); --no-mirror writes the "
                             f"part as solved")
        axis = int(np.argmax(np.abs(normal)))
        if 1.0 - abs(normal[axis]) > rtol:
            raise InputError(f"--mirror: the symmetry face '{name}' is a plane not "
                             f"perpendicular to x, y or z (normal {np.round(normal, 6)}); "
                             f"--no-mirror writes the part as solved")
        planes.append(SymmetryPlane(name, axis, float(centre[axis]), rtol * diam))
    axes = [p.axis for p in planes]
    if len(set(axes)) < len(axes):
        raise InputError("--mirror: two symmetry faces are planes perpendicular to the same "
                         f"axis ({', '.join(map(str, planes))}); --no-mirror writes the part "
                         f"as solved")
    return planes


def reflect(data, plane: SymmetryPlane):
    """``data`` (a pyvista dataset) and its mirror image about ``plane`` as one
    UnstructuredGrid (the points on the plane twice), its arrays reflected (module
    docstring)."""
    import pyvista as pv
    from vtkmodules.vtkFiltersGeneral import vtkReflectionFilter

    alg = vtkReflectionFilter()
    alg.SetInputData(data)
    alg.SetPlane((vtkReflectionFilter.USE_X, vtkReflectionFilter.USE_Y,
                  vtkReflectionFilter.USE_Z)[plane.axis])
    alg.SetCenter(plane.offset)
    alg.SetCopyInput(True)
    alg.SetFlipAllInputArrays(True)
    alg.Update()
    return pv.wrap(alg.GetOutput())


def mirror_surface(surface, planes):
    """The closed triangulated ``surface`` (pyvista PolyData, outward) reflected about every
    plane of ``planes`` and merged along it (module docstring).  The triangles on each plane
    are found on the input, in double precision, before any reflection.  Returns a new
    PolyData without point or cell data."""
    surf = surface.copy()
    surf.clear_data()
    pts = np.asarray(surf.points)[np.asarray(surf.faces).reshape(-1, 4)[:, 1:]]
    marks = [f"on_{plane.name}" for plane in planes]
    for mark, plane in zip(marks, planes):
        on = np.abs(pts[:, :, plane.axis] - plane.offset) <= plane.tol
        surf.cell_data[mark] = on.all(axis=1).astype(np.uint8)
    for mark, plane in zip(marks, planes):
        both = reflect(surf.extract_cells(np.flatnonzero(surf.cell_data[mark] == 0)), plane)
        surf = both.clean(tolerance=plane.tol, produce_merge_map=False).extract_surface(
            pass_pointid=False, pass_cellid=False, algorithm="dataset_surface")
    surf.clear_data()
    return surf


def mirror_solid(solid, planes):
    """The clipped solid (pyvista UnstructuredGrid) with its point and cell data reflected
    about every plane of ``planes``, the points on a plane merged (a merged point keeps the
    original's values: no averaging)."""
    for plane in planes:
        solid = reflect(solid, plane).clean(tolerance=plane.tol, produce_merge_map=False,
                                            average_point_data=False)
    return solid
