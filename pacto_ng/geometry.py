"""A case's domain: any 2D or 3D netgen.occ geometry, a CAD file, a mesh file, a rectangle or a box.

The dimension comes from the geometry.  A case's ``geometry(params)`` returns one of

* a **2D netgen.occ shape** (a ``Face``, or ``Glue([...])`` of several faces) whose faces and
  edges carry netgen.occ's own names (``face.name``, ``edge.name``, ``vertex.name``, and
  ``.maxh`` for local refinement).  Faces name the design domain (``design``) and the passive
  regions; edges name the boundaries (inlet, zero pressure, supports, symmetry, loads, ports);
  a named vertex is a point port or a point load.  Unnamed edges are called ``default``;
* a **3D netgen.occ shape** (a ``Solid``, or ``Glue([...])`` of solids), meshed with Netgen
  tetrahedra: solids name the design domain (``solid.name = "design"``) and the passive
  regions (a chamber), faces the boundaries, edges and vertices the points (``default``
  where unnamed);
* a :class:`~pacto_ng.mesh.Layout` (the rectangle helper: named segments, passive rectangles,
  ports), which can also be meshed as structured quads (``nelx``, ``nely``), or a
  :class:`~pacto_ng.box.Box` (its 3D counterpart: named patches on its sides, passive blocks,
  points), meshed as tetrahedra or structured hexahedra (``nelx``, ``nely``, ``nelz``);
* a **CAD file** (``.step``, ``.stp``, ``.brep``, ``.iges``, ``.igs``) or a shape read from one by
  :func:`load_cad` (then named in the case's script): 3D where it holds solids;
* a **mesh file** (Gmsh ``.msh`` with physical groups as names, or Netgen ``.vol``; 2D or 3D),
  or an ``ngsolve.Mesh``: used as it is (``maxh`` does not apply).

This module reads CAD and mesh files (:func:`load_cad`, :func:`load_mesh`); each kind knows
its size and meshes itself (:mod:`pacto_ng.geometry_kinds`), and
:func:`pacto_ng.meshing.mesh_geometry` turns any of them into a
:class:`~pacto_ng.mesh.Meshed` domain; the case's set-up then refers to the names, and
:func:`pacto_ng.setup_names.check_setup_names` says which name is missing and which exist.
"""
from __future__ import annotations

import os
from pathlib import Path

from .errors import InputError

CAD_SUFFIXES = (".step", ".stp", ".brep", ".iges", ".igs")
MESH_SUFFIXES = (".msh", ".vol", ".vol.gz")


def load_cad(path: str | os.PathLike):
    """The netgen.occ shape of a STEP, BREP or IGES file (names stored in the file are kept;
    name the rest in the case's script, e.g. ``shape.edges.Min(occ.X).name = "fixed"``)."""
    from netgen import occ

    fp = Path(path)
    if fp.suffix.lower() not in CAD_SUFFIXES:
        raise InputError(f"geometry: '{path}' is not a CAD file ({', '.join(CAD_SUFFIXES)})")
    if not fp.is_file():
        raise InputError(f"geometry: CAD file '{path}' does not exist")
    try:
        shape = occ.OCCGeometry(str(fp)).shape
    except RuntimeError as err:
        raise InputError(f"geometry: cannot read CAD file '{path}' ({err})") from None
    if len(shape.faces) == 0:
        raise InputError(f"geometry: CAD file '{path}' holds no face")
    return shape


def load_mesh(path: str | os.PathLike):
    """An ``ngsolve.Mesh`` from a Gmsh ``.msh`` file (physical groups become the region and
    boundary names: surface groups in 2D, volume groups in 3D) or a Netgen ``.vol`` file."""
    import ngsolve

    fp = Path(path)
    if not fp.is_file():
        raise InputError(f"geometry: mesh file '{path}' does not exist")
    name = fp.name.lower()
    try:
        if name.endswith(".msh"):
            from netgen.read_gmsh import ReadGmsh

            ngm = ReadGmsh(str(fp))
        elif name.endswith((".vol", ".vol.gz")):
            from netgen.meshing import Mesh as NGMesh

            ngm = NGMesh()  # Load takes the file's dimension
            ngm.Load(str(fp))
        else:
            raise InputError(f"geometry: '{path}' is not a mesh file ({', '.join(MESH_SUFFIXES)})")
    except (RuntimeError, ValueError, IndexError, KeyError) as err:
        raise InputError(f"geometry: cannot read mesh file '{path}' ({type(err).__name__}: "
                         f"{err})") from None
    mesh = ngsolve.Mesh(ngm)
    if mesh.ne == 0:
        raise InputError(f"geometry: mesh file '{path}' holds no element")
    return mesh


def is_occ_shape(obj) -> bool:
    """A netgen.occ shape (2D or 3D)."""
    from netgen import occ

    return isinstance(obj, occ.TopoDS_Shape)


def is_solid(shape) -> bool:
    """A 3D shape: it holds solids (a 2D one holds faces only)."""
    return len(shape.solids) > 0
