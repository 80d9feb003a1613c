"""Boxes with named boundary patches, passive blocks and points, meshed two ways (3D).

A :class:`Box` is the 3D counterpart of :class:`~pacto_ng.mesh.Layout`: the box
``[0, W] x [0, H] x [0, D]`` (``width`` along x, ``height`` along y, ``depth`` along z) whose
six sides (``xmin``, ``xmax``, ``ymin``, ``ymax``, ``zmin``, ``zmax``) carry named rectangular
:class:`Patch` es, passive :class:`Block` s inside it (``solid``, ``void`` or a pressurised
chamber) and named points.  It is meshed either with Netgen tetrahedra (:func:`netgen_box_mesh`)
or as a structured grid of ``nelx x nely x nelz`` hexahedra (:func:`structured_box`, the
TOPress3D set-up with ``Box(nelx, nely, nelz)``: unit cubes), with the *same* names in both:

* materials: ``design`` and the names of the blocks;
* boundaries: the patch names, ``free`` for the rest of the outer boundary, and for a block
  with ``boundary=NAME`` (a chamber) its faces inside the box get that name;
* points (co-dimension 3): the point names.  A point at a corner of the box, of a patch or of
  a block is that vertex of the mesh; any other point is the mesh node nearest to it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the sides of a box: (axis, 0 for the lower side or 1 for the upper)
_OCC_GAP = 1e-6  # netgen.occ's bounding boxes are larger than the shape by 1e-7
SIDES = {"xmin": (0, 0), "xmax": (0, 1), "ymin": (1, 0), "ymax": (1, 1), "zmin": (2, 0),
         "zmax": (2, 1)}


@dataclass(frozen=True)
class Patch:
    """A named rectangle on the box's ``side``: ``lo``, ``hi`` its corners in the side's two
    other coordinates, in axis order (``(y, z)`` on ``xmin``/``xmax``, ``(x, z)`` on
    ``ymin``/``ymax``, ``(x, y)`` on ``zmin``/``zmax``); None: the whole side."""

    name: str
    side: str
    lo: tuple[float, float] | None = None
    hi: tuple[float, float] | None = None

    def __post_init__(self):
        if self.side not in SIDES:
            raise ValueError(f"patch '{self.name}': side must be one of {', '.join(SIDES)}, "
                             f"not '{self.side}'")
        if (self.lo is None) != (self.hi is None):
            raise ValueError(f"patch '{self.name}': give both lo and hi, or neither")
        if self.lo is not None and not all(b > a for a, b in zip(self.lo, self.hi)):
            raise ValueError(f"patch '{self.name}' is empty")


@dataclass(frozen=True)
class Block:
    """A passive box ``[x0, x1] x [y0, y1] x [z0, z1]`` (``lo``, ``hi``; blocks do not
    overlap).  ``kind`` is ``solid`` or ``void``; ``boundary`` names its faces that lie inside
    the box (``inlet`` for a chamber)."""

    name: str
    kind: str
    lo: tuple[float, float, float]
    hi: tuple[float, float, float]
    boundary: str | None = None

    def __post_init__(self):
        if self.kind not in ("solid", "void"):
            raise ValueError(f"block '{self.name}': kind must be 'solid' or 'void', not "
                             f"'{self.kind}'")
        if not all(b > a for a, b in zip(self.lo, self.hi)):
            raise ValueError(f"block '{self.name}' is empty")

    def contains(self, p, tol=0.0) -> np.ndarray:
        """Whether the points ``p`` (last axis x, y, z; broadcast) lie in the block."""
        p = np.asarray(p, dtype=float)
        inside = np.ones(p.shape[:-1], dtype=bool)
        for a in range(3):
            inside &= (p[..., a] > self.lo[a] - tol) & (p[..., a] < self.hi[a] + tol)
        return inside

    def on_boundary(self, p, tol) -> np.ndarray:
        """Whether the points ``p`` lie on the block's surface."""
        p = np.asarray(p, dtype=float)
        near = np.zeros(p.shape[:-1], dtype=bool)
        for a in range(3):
            near |= (np.abs(p[..., a] - self.lo[a]) < tol) | (np.abs(p[..., a] - self.hi[a]) < tol)
        return self.contains(p, tol) & near


@dataclass(frozen=True)
class Box:
    """A box with named boundary patches, passive blocks and points (module docstring)."""

    width: float
    height: float
    depth: float
    patches: tuple[Patch, ...] = ()
    blocks: tuple[Block, ...] = ()
    points: tuple[tuple[str, tuple[float, float, float]], ...] = ()

    def __post_init__(self):
        if min(self.width, self.height, self.depth) <= 0:
            raise ValueError("box width, height and depth must be positive")

    @property
    def size(self) -> np.ndarray:
        return np.array([self.width, self.height, self.depth], dtype=float)

    @property
    def tol(self) -> float:
        return 1e-9 * float(self.size.max())

    def outer_name(self, lo, hi=None, tol=None) -> str:
        """The name of the outer boundary between the corners ``lo`` and ``hi`` of a face's
        bounding box (a point with ``hi`` None: a grid face's centre): the first patch that
        holds it, else ``free``.  ``tol``: the distance within which a point lies on a plane
        (default ``self.tol``)."""
        tol = self.tol if tol is None else tol
        lo = np.asarray(lo, dtype=float)
        hi = lo if hi is None else np.asarray(hi, dtype=float)
        for patch in self.patches:
            axis, end = SIDES[patch.side]
            at = end * self.size[axis]
            if abs(lo[axis] - at) > tol or abs(hi[axis] - at) > tol:
                continue
            if patch.lo is None:
                return patch.name
            other = [a for a in range(3) if a != axis]
            if all(patch.lo[i] - tol <= lo[a] and hi[a] <= patch.hi[i] + tol
                   for i, a in enumerate(other)):
                return patch.name
        return "free"

    def on_outer(self, p, tol=None) -> bool:
        tol = self.tol if tol is None else tol
        p = np.asarray(p, dtype=float)
        return bool(np.any(np.abs(p) < tol) or np.any(np.abs(p - self.size) < tol))

    def patch_rectangles(self):
        """``(side, lo, hi)`` of every patch that is not a whole side."""
        return [(pt.side, pt.lo, pt.hi) for pt in self.patches if pt.lo is not None]


# ------------------------------------------------------------------------------------------
def box_shape(box: Box):
    """The netgen.occ shape of ``box``: solids named ``design`` and by the blocks, faces by
    the patches (``free`` elsewhere on the outer boundary) and the blocks' ``boundary``,
    vertices by the points that are corners."""
    from netgen import occ

    body = occ.Box((0, 0, 0), tuple(box.size))
    solids = []
    for blk in box.blocks:
        b = occ.Box(tuple(blk.lo), tuple(blk.hi))
        body = body - b
        b.solids.name = blk.name
        solids.append(b)
    body.solids.name = "design"
    faces = [_patch_face(box, side, lo, hi) for side, lo, hi in box.patch_rectangles()]
    shape = occ.Glue([body] + solids + faces) if solids or faces else body
    tol = box.tol + _OCC_GAP
    for f in shape.faces:
        # by the bounding box, not the centre: the rest of a side around a patch is a frame
        # whose centre is the patch's
        lo, hi = (np.array([q.x, q.y, q.z]) for q in f.bounding_box)
        if box.on_outer(lo, tol) and box.on_outer(hi, tol):
            f.name = box.outer_name(lo, hi, tol)
        else:
            f.name = None
            for blk in box.blocks:
                if blk.boundary and blk.on_boundary(lo, tol) and blk.on_boundary(hi, tol):
                    f.name = blk.boundary
    for name, xyz in box.points:
        v = shape.vertices.Nearest(tuple(xyz))
        if _at(v, xyz, box):
            v.name = name
    return shape


def _patch_face(box: Box, side: str, lo, hi):
    """The rectangle of a patch, a face lying on the box's side (glued in to split it)."""
    from netgen import occ

    axis, end = SIDES[side]
    other = [a for a in range(3) if a != axis]
    corner = [0.0, 0.0, 0.0]
    corner[axis] = end * box.size[axis]
    size = [0.0, 0.0, 0.0]
    for i, a in enumerate(other):
        corner[a] = lo[i]
        size[a] = hi[i] - lo[i]
    p = [occ.Pnt(*corner)]
    for a in other:
        q = list(corner)
        q[a] += size[a]
        p.append(occ.Pnt(*q))
    far = list(corner)
    for a in other:
        far[a] += size[a]
    wire = occ.Wire([occ.Segment(p[0], p[1]), occ.Segment(p[1], occ.Pnt(*far)),
                     occ.Segment(occ.Pnt(*far), p[2]), occ.Segment(p[2], p[0])])
    return occ.Face(wire)


def _at(vertex, xyz, box: Box) -> bool:
    p = vertex.p
    return abs(p.x - xyz[0]) + abs(p.y - xyz[1]) + abs(p.z - xyz[2]) <= box.tol


def netgen_box_mesh(box: Box, maxh: float):
    """Netgen tetrahedral mesh of ``box`` with element size ``maxh`` (an ngsolve.Mesh)."""
    from netgen import occ
    from netgen.meshing import Element0D
    import ngsolve

    shape = box_shape(box)
    ngm = occ.OCCGeometry(shape).GenerateMesh(maxh=maxh)
    inner = [(name, xyz) for name, xyz in box.points
             if not _at(shape.vertices.Nearest(tuple(xyz)), xyz, box)]
    if inner:
        coords = np.array([list(p) for p in ngm.Coordinates()])
        for name, xyz in inner:
            k = int(np.argmin(((coords - np.asarray(xyz)) ** 2).sum(axis=1)))
            ngm.Add(Element0D(k + 1, index=ngm.AddRegion(name, dim=0)))
    return ngsolve.Mesh(ngm)


def structured_box(box: Box, nelx: int, nely: int, nelz: int):
    """Structured ``nelx x nely x nelz`` hexahedral mesh of ``box`` (an ngsolve.Mesh).

    Element ``(i, j, k)`` (i along x, j along y, k along z, from the origin) is the NGSolve
    element ``(k * nely + j) * nelx + i``.  Region membership is decided by the element's
    centroid (a block smaller than an element: the element holding its centre), boundary names
    by the face's centre, points by the nearest node.  Boundary faces' normals point out of
    the box and out of the blocks."""
    from netgen.meshing import Element0D
    from netgen.meshing import Mesh as NGMesh
    import ngsolve

    n = np.array([nelx, nely, nelz])
    if np.any(n < 1):
        raise ValueError("nelx, nely and nelz must be positive")
    axes = [np.linspace(0.0, box.size[a], n[a] + 1) for a in range(3)]
    m = NGMesh(dim=3)
    # node (i, j, k) is point (k * (nely + 1) + j) * (nelx + 1) + i
    grid = np.meshgrid(*axes, indexing="ij")
    m.AddPoints(np.c_[tuple(g.ravel("F") for g in grid)])

    def node(i, j, k):
        return (k * (nely + 1) + j) * (nelx + 1) + i

    i, j, k = (g.ravel("F") for g in np.meshgrid(*(np.arange(c) for c in n), indexing="ij"))
    corners = np.stack([node(i, j, k), node(i + 1, j, k), node(i + 1, j + 1, k),
                        node(i, j + 1, k), node(i, j, k + 1), node(i + 1, j, k + 1),
                        node(i + 1, j + 1, k + 1), node(i, j + 1, k + 1)], axis=1)
    m.SetMaterial(1, "design")
    m.AddElements(dim=3, index=1, data=corners.astype(np.int32), base=0)
    mat = _element_materials(box, axes, n)
    elements = m.Elements3D()
    for r, blk in enumerate(box.blocks):
        m.SetMaterial(r + 2, blk.name)
        for e in np.flatnonzero(mat.ravel("F") == r + 1):
            elements[int(e)].index = r + 2
    _add_faces(m, _boundary_faces(box, axes, n, mat, node))
    for name, xyz in box.points:
        ijk = [int(np.argmin(np.abs(axes[a] - xyz[a]))) for a in range(3)]
        m.Add(Element0D(int(node(*ijk)) + 1, index=m.AddRegion(name, dim=0)))
    return ngsolve.Mesh(m)


def _element_materials(box: Box, axes, n) -> np.ndarray:
    """``(nelx, nely, nelz)`` array: 0 for design, r + 1 for the r-th block, by centroid."""
    centres = np.stack(np.meshgrid(*(0.5 * (ax[:-1] + ax[1:]) for ax in axes), indexing="ij"),
                       axis=-1)
    mat = np.zeros(tuple(n), dtype=int)
    for r, blk in enumerate(box.blocks):
        inside = blk.contains(centres)
        if not inside.any():
            # a block smaller than an element: the element holding its centre represents it
            mid = 0.5 * (np.asarray(blk.lo) + np.asarray(blk.hi))
            idx = tuple(min(int(mid[a] / box.size[a] * n[a]), n[a] - 1) for a in range(3))
            inside[idx] = True
        mat[inside & (mat == 0)] = r + 1
    return mat


def _face_nodes(node, a, fixed, lo_b, lo_c):
    """The four nodes of the grid faces normal to axis ``a`` at node index ``fixed`` whose
    lower corners have indices ``lo_b``, ``lo_c`` along the two other axes, ordered so that
    the normal points along +a."""
    b, c = [x for x in range(3) if x != a]

    def at(db, dc):
        ijk = [None, None, None]
        ijk[a], ijk[b], ijk[c] = np.full_like(lo_b, fixed), lo_b + db, lo_c + dc
        return node(*ijk)

    quad = np.stack([at(0, 0), at(1, 0), at(1, 1), at(0, 1)], axis=1)
    return quad if a != 1 else quad[:, ::-1]  # e_x x e_z = -e_y


def _boundary_faces(box: Box, axes, n, mat, node):
    """``{(name, domin, domout): quads}`` of the outer boundary and the blocks' named faces."""
    out: dict[tuple, list] = {}
    for side, (a, end) in SIDES.items():
        b, c = [x for x in range(3) if x != a]
        lo_b, lo_c = (g.ravel() for g in np.meshgrid(np.arange(n[b]), np.arange(n[c]),
                                                     indexing="ij"))
        centre = np.zeros((lo_b.size, 3))
        centre[:, a] = end * box.size[a]
        centre[:, b] = 0.5 * (axes[b][lo_b] + axes[b][lo_b + 1])
        centre[:, c] = 0.5 * (axes[c][lo_c] + axes[c][lo_c + 1])
        quads = _face_nodes(node, a, end * n[a], lo_b, lo_c)
        if end == 0:
            quads = quads[:, ::-1]  # outward: along -a
        ijk = [None, None, None]
        ijk[a], ijk[b], ijk[c] = np.full_like(lo_b, end * (n[a] - 1)), lo_b, lo_c
        inner = mat[tuple(ijk)] + 1
        names = np.array([box.outer_name(p) for p in centre], dtype=object)
        for key in set(zip(names, inner)):
            sel = (names == key[0]) & (inner == key[1])
            out.setdefault((key[0], int(key[1]), 0), []).append(quads[sel])
    for r, blk in enumerate(box.blocks):
        if not blk.boundary:
            continue
        inside = mat == r + 1
        for a in range(3):
            lower = np.swapaxes(np.swapaxes(inside, 0, a)[:-1], 0, a)
            upper = np.swapaxes(np.swapaxes(inside, 0, a)[1:], 0, a)
            for idx in zip(*np.nonzero(lower != upper)):
                up = list(idx)
                up[a] += 1
                b, c = [x for x in range(3) if x != a]
                quad = _face_nodes(node, a, idx[a] + 1, np.array([idx[b]]), np.array([idx[c]]))
                outside = tuple(up) if inside[idx] else idx
                if not inside[idx]:
                    quad = quad[:, ::-1]  # out of the block: along -a
                key = (blk.boundary, r + 2, int(mat[outside]) + 1)
                out.setdefault(key, []).append(quad)
    return {key: np.vstack(q) for key, q in out.items()}


def _add_faces(m, faces) -> None:
    """One face descriptor per (name, domain inside, domain outside), its quads added."""
    from netgen.meshing import FaceDescriptor

    bcs: dict[str, int] = {}
    for surf, ((name, domin, domout), quads) in enumerate(sorted(faces.items())):
        bc = bcs.setdefault(name, len(bcs) + 1)
        fd = m.Add(FaceDescriptor(surfnr=surf + 1, domin=domin, domout=domout, bc=bc))
        m.SetBCName(fd - 1, name)
        m.AddElements(dim=2, index=fd, data=quads.astype(np.int32), base=0)
