"""The displacement gradient ``G = ∇u`` the strain energies take: its dimension, and the planes a
2D one stands for (strain: ``F33 = 1``; stress: ``S33 = 0``)."""
from __future__ import annotations

PLANES = ("strain", "stress")


def dimension(G, plane: str = "strain") -> int:
    """The dimension ``d`` of the gradient ``G`` (d x d), after checking that ``plane`` applies
    to it: ``"strain"`` or ``"stress"`` in 2D, only ``"strain"`` (no meaning, the default) in
    3D; ``ValueError`` otherwise."""
    if plane not in PLANES:
        raise ValueError(f"plane must be 'strain' or 'stress' (got '{plane}')")
    d = int(G.dims[0])
    if d not in (2, 3):
        raise ValueError(f"the displacement gradient must be 2x2 or 3x3 (got {d}x{d})")
    if d == 3 and plane == "stress":
        raise ValueError("plane=stress applies to 2D meshes only: a 3D mesh is the solid itself "
                         "(use plane=strain, the default, which 3D ignores)")
    return d
