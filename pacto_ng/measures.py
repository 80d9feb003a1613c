"""The strain and stress measures of an analysed state, by the run's model: what design.vtu
holds (:func:`pacto_ng.outputs.write_vtu`) and what a part's export samples from the run
(:mod:`pacto_ng.post.part2d`, :mod:`pacto_ng.post.post3d`)."""
from __future__ import annotations

from .physics.materials import first_piola_kirchhoff, green_lagrange, second_piola_kirchhoff
from .problem import Problem


def tensor_components(dim: int) -> list:
    """``((i, j), name)`` of a symmetric tensor's components written to design.vtu: xx, yy,
    xy in 2D; xx, yy, zz, xy, yz, xz in 3D."""
    if dim == 3:
        return [((0, 0), "xx"), ((1, 1), "yy"), ((2, 2), "zz"), ((0, 1), "xy"),
                ((1, 2), "yz"), ((0, 2), "xz")]
    return [((0, 0), "xx"), ((1, 1), "yy"), ((0, 1), "xy")]


def strain_stress_measures(problem: Problem) -> dict:
    """The strain and stress CFs of the analysed state (2x2 in-plane in 2D, 3x3 in 3D: the
    size of ``Grad(u)``), by model: ``linear``: ε and σ; ``gnl``/``neohookean``:
    Green–Lagrange ``E_GL`` and the second Piola–Kirchhoff ``S`` (``F⁻¹ ∂φ/∂F`` by automatic
    differentiation); ``wang``: ``E_W1``, ``E_W2`` (thesis eqs 5.4–5.5) and ``S`` (eq. 5.3).
    design.vtu holds their element means (:func:`tensor_components`)."""
    from ngsolve import Grad

    mech = problem.mech
    G, c = Grad(mech.u), mech.coeffs
    model = problem.params.model
    if model == "wang":
        wm = mech.energy  # the WangModel (make_energy passes the model as the energy)
        return {"E_W1": wm.strain_w1(G, c), "E_W2": wm.strain_w2(G, c), "S": wm.stress(G, c)}
    phi = lambda A: mech.energy(A, c)  # noqa: E731
    if model == "linear":
        return {"strain": 0.5 * (G + G.trans), "stress": first_piola_kirchhoff(phi, G)}
    return {"E_GL": green_lagrange(G), "S": second_piola_kirchhoff(phi, G)}
