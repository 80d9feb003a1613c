"""Domains of the 3D cases, as named netgen.occ solids (docs/guide.md, "Your own geometry").

Every domain is a box ``[0, L] x [0, H] x [0, D]`` cut into solids that carry the region names
(``design`` and the passive ones) and faces that carry the boundary names.  A face is named
after the part of the box it lies on; a face that is named nothing is ``free`` (no support, no
load; the Darcy pressure's natural no-flux condition).  A half or a quarter of a symmetric body
names its cut faces ``symmetry`` (y = 0) and ``symmetry_z`` (z = D): the cases hold them in the
normal direction, and no fluid crosses them.

* :func:`cantilever` — a beam clamped at x = 0 (``fixed``), loaded on its end face x = L
  (``load``).
* :func:`pneunet` — a PneuNet member, one half in depth: a box chamber (passive void
  ``chamber``, its walls the pressure ``inlet``) inside it; ``fixed`` at x = 0, the end face
  ``tip`` (the output), the rest of the outer faces ``zero_pressure``.
* :func:`pa_mechanism` — the pressure-actuated inverter or gripper, a quarter (symmetric in y
  and in z): the ``inlet`` face x = 0; a passive solid ``block`` under the clamped strip
  ``fixed`` of the top face; the rest of the top face, the right face and the front face z = 0
  ``zero_pressure``; the output patch ``output`` on the right face (inverter) or the jaw pad's
  inner face (gripper, with the passive void ``jaw_void`` and solid ``jaw_pad``).
"""
from __future__ import annotations

from pacto_ng.derive import se_default
from pacto_ng.params import Parameters
from pacto_ng.physics.loads import Port, Spring
from pacto_ng.physics.mechanics import Supports
from pacto_ng.setup import Pressure, Setup

#: the pressure-actuated mechanism's body L x H x D (its quarter: H and D/2), metres
PA_MECHANISM = (0.2, 0.1, 0.04)
#: OCC pads bounding boxes by 1e-7; the domains are millimetres and larger
_TOL = 1e-6


def _box(x0, y0, z0, x1, y1, z1, name: str):
    from netgen import occ

    solid = occ.Box((x0, y0, z0), (x1, y1, z1))
    solid.solids.name = name
    solid.faces.name = "free"
    return solid


def _name_faces(shape, where, name: str) -> int:
    """Name every face of ``shape`` lying in the plane ``where = (axis, value)`` (and inside
    the optional box ``where[2]`` = ((lo), (hi)))."""
    axis, value = where[:2]
    box = where[2] if len(where) > 2 else None
    n = 0
    for face in shape.faces:
        lo, hi = face.bounding_box
        if hi[axis] - lo[axis] > 3 * _TOL or abs(face.center[axis] - value) > _TOL:
            continue
        if box is not None and not all(box[0][k] - _TOL <= lo[k] and hi[k] <= box[1][k] + _TOL
                                       for k in range(3)):
            continue
        face.name = name
        n += 1
    if n == 0:
        raise ValueError(f"no face named '{name}': nothing lies at {where}")
    return n


def cantilever(length: float = 1.0, height: float = 0.25, depth: float = 0.125):
    """A beam ``length x height x depth``: ``fixed`` at x = 0, ``load`` at x = L."""
    from netgen import occ

    shape = occ.Glue([_box(0, 0, 0, length, height, depth, "design")])
    _name_faces(shape, (0, 0.0), "fixed")
    _name_faces(shape, (0, length), "load")
    return shape


def pneunet(length: float = 0.1, height: float = 0.05, depth: float = 0.03,
            chamber=(0.2, 0.2, 0.8, 0.4), chamber_depth: float = 2 / 3):
    """One half (z ∈ [0, D/2], ``symmetry_z`` at z = D/2) of a PneuNet member ``L x H x D``.

    ``chamber`` = (x0, y0, x1, y1) as fractions of L and H; the chamber spans the middle
    ``chamber_depth`` of the depth (its half here reaches the symmetry face)."""
    from netgen import occ

    L, H, Dh = length, height, 0.5 * depth
    x0, y0, x1, y1 = chamber[0] * L, chamber[1] * H, chamber[2] * L, chamber[3] * H
    z0 = Dh * (1.0 - chamber_depth)
    room = _box(x0, y0, z0, x1, y1, Dh, "chamber")
    body = _box(0, 0, 0, L, H, Dh, "design") - room
    body.solids.name = "design"
    shape = occ.Glue([body, room])
    _name_faces(shape, (0, 0.0), "fixed")
    _name_faces(shape, (0, L), "tip")
    for axis, value in ((1, 0.0), (1, H), (2, 0.0)):
        _name_faces(shape, (axis, value), "zero_pressure")
    _name_faces(shape, (2, Dh), "symmetry_z")
    inner = ((x0, y0, z0), (x1, y1, Dh))
    for axis, value in ((0, x0), (0, x1), (1, y0), (1, y1), (2, z0)):
        _name_faces(shape, (axis, value, inner), "inlet")
    return shape


def pa_mechanism(length: float = 0.2, height: float = 0.1, depth: float = 0.04,
                 gripper: bool = False, output_height: float = 0.05):
    """A quarter (y ∈ [0, H], z ∈ [0, D/2]) of the pressure-actuated inverter or gripper
    ``L x 2H x D``, symmetric about y = 0 (``symmetry``) and z = D/2 (``symmetry_z``).

    Block and clamp: L/20 x H/20 at the top-left, as in 2D.  The inverter's output patch is
    the strip y ∈ [0, output_height·H] of the right face; the gripper's is the inner face
    (y = 0.2H) of the jaw pad."""
    from netgen import occ

    L, H, Dh = length, height, 0.5 * depth
    parts = [_box(0, H - H / 20, 0, L / 20, H, Dh, "block")]
    if gripper:
        parts += [_box(0.8 * L, 0, 0, L, 0.2 * H, Dh, "jaw_void"),
                  _box(0.8 * L, 0.2 * H, 0, L, 0.25 * H, Dh, "jaw_pad")]
    else:
        parts.append(_box(L - L / 20, 0, 0, L, output_height * H, Dh, "design"))
    body = _box(0, 0, 0, L, H, Dh, "design")
    for part in parts:
        body = body - part
    body.solids.name = "design"
    shape = occ.Glue([body] + parts)
    _name_faces(shape, (0, 0.0), "inlet")
    _name_faces(shape, (1, H, ((0, H, 0), (L / 20, H, Dh))), "fixed")
    _name_faces(shape, (1, H, ((L / 20, H, 0), (L, H, Dh))), "zero_pressure")
    _name_faces(shape, (0, L), "zero_pressure")
    _name_faces(shape, (2, 0.0), "zero_pressure")
    _name_faces(shape, (1, 0.0), "symmetry")
    _name_faces(shape, (2, Dh), "symmetry_z")
    if gripper:
        # the jaw void's faces inside the body are free: the gripped object is not loaded
        _name_faces(shape, (1, 0.2 * H, ((0.8 * L, 0.2 * H, 0), (L, 0.2 * H, Dh))), "output")
    else:
        _name_faces(shape, (0, L, ((L, 0, 0), (L, output_height * H, Dh))), "output")
    return shape


def pa_mechanism_setup(p: Parameters, *, gripper: bool) -> Setup:
    """The set-up of :func:`pa_mechanism` of the size :data:`PA_MECHANISM`: pa-inverter-3d and
    (``gripper``) pa-gripper-3d."""
    length, height, depth = PA_MECHANISM
    volume = length * height * 0.5 * depth
    direction = (0.0, 1.0, 0.0) if gripper else (1.0, 0.0, 0.0)
    zero = ("zero_pressure", "fixed") + (() if gripper else ("output",))
    return Setup(supports=Supports(clamp=("fixed",), fix_y=("symmetry",),
                                   fix_z=("symmetry_z",)),
                 springs=(Spring("output", p.k_out, direction),),
                 port=Port("output", tuple(-c for c in direction)),
                 solid=("block", "jaw_pad") if gripper else ("block",),
                 void=("jaw_void",) if gripper else (), objective="mechanism",
                 pressure=Pressure(inlet=("inlet",), zero=zero),
                 se_max=se_default(p, volume),
                 # -Δ/SE is of order 3 / (P_in L D/2), as the 2D cases' 3 / (P_in L t)
                 objective_ref=3.0 / (p.load * length * 0.5 * depth))
