"""Shared set-up of the nonlinear-mechanics tests: the small cantilever of cases/cantilever.py.

Layout 1.0 x 0.25 m, left edge clamped, the tip load spread over y in [0.1, 0.15] of the right
edge; E1 = 3e9, E0 = 3e3, ν = 0.4, t = 0.1 m, SIMP p = 3.
"""
from __future__ import annotations

from pacto_ng.interpolation import simp_cf
from pacto_ng.mesh import Layout, Segment, netgen_mesh, structured_mesh
from pacto_ng.physics.loads import PointLoad
from pacto_ng.physics.materials import get_material, jacobian
from pacto_ng.physics.mechanics import Mechanics, Supports
from pacto_ng.physics.newton import NewtonSettings
from pacto_ng.physics.wang import wang_model

E1, E0, NU, T, PENAL = 3e9, 3e3, 0.4, 0.1, 3.0
MODELS = ("linear", "gnl", "neohookean", "wang")


def cantilever_layout():
    return Layout(1.0, 0.25, segments=(Segment("fixed", (0.0, 0.0), (0.0, 0.25)),
                                       Segment("load", (1.0, 0.1), (1.0, 0.15))))


def cantilever_mesh(kind: str = "trig"):
    """``trig``: Netgen triangles of size 0.0625 (~150 elements); ``quad``: 16 x 8 quads."""
    lay = cantilever_layout()
    if kind == "trig":
        return netgen_mesh(lay, 0.0625)
    return structured_mesh(lay, 16, 8)


def energy_and_guard(model, plane="strain", gamma_fn=None, **wang_kw):
    """``(energy, guard, linear)`` of a named model with SIMP on the field ``rho_bar``."""
    modulus = lambda c: simp_cf(c["rho_bar"], E0, E1, PENAL)
    if model == "wang":
        energy, guard = wang_model(modulus, NU, plane, "rho_bar", PENAL, gamma_fn=gamma_fn,
                                   **wang_kw)
        return energy, guard, False
    mat = get_material(model)
    energy = lambda G, c: mat.energy(G, modulus(c), NU, plane)
    guard = (lambda G, c: jacobian(G)) if mat.needs_positive_J else None
    return energy, guard, mat.linear


def cantilever(mesh, model, order=1, load=2e5, plane="strain", newton=None, gamma_fn=None,
               realcompile=False, **wang_kw):
    """A :class:`Mechanics` block of the cantilever with a downward tip load ``load`` (N)."""
    energy, guard, linear = energy_and_guard(model, plane, gamma_fn, **wang_kw)
    newton = newton or NewtonSettings(rtol=1e-12, initial_increment=0.25)
    return Mechanics(mesh, order=order, energy=energy, supports=Supports(clamp=("fixed",)),
                     loads=(PointLoad("load", (0.0, -load)),), thickness=T, guard=guard,
                     linear=linear, newton=newton, realcompile=realcompile)
