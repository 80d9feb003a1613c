"""A pressure-actuated gripper cast in silicone, in real units (docs/guide.md, "Silicone cases").

What it shows: the pa-gripper as it would be cast: an 80 x 20 mm jaw (solved on its 40 x 20 mm
half, mirrored about the symmetry line), 10 mm thick out of plane, in Dragon Skin 30 (the
``dragonskin-30`` preset of pacto_ng/physics/presets.py: its published Yeoh fit, μ0 = 307 kPa),
under a 10 kPa inlet pressure that follows the deforming walls (a follower load).  The pressure
closes the jaw onto the symmetry line.

The pa-gripper's domain (geometries/pa_mechanism.py) at this size: inlet on the left edge, zero
pressure on the top and right edges, clamp and passive solid block at the top-left corner,
passive void x ∈ [32, 40] mm, y ∈ [0, 4] mm (the gripped object's place) and a passive solid
jaw pad above it.  Output: the jaw pad's right edge from its inner corner (40, 4) mm up
0.8 mm (two element edges, "output_edge"), Δ = the edge's mean of -u_y (the jaw closes), with
an output spring k_out = 900 N/m on that edge (k/2 times its mean of u_y²; a gripped object of
about 1 N/mm; 0.1 of the jaw's E1 t).  The edge lies on the passive pad in the design and in
its part alike; a spring at the corner point crushed the part's finer elements there before
the full load (docs/benchmarks.md, "The built-in cases at defaults").  Model: Wang's
interpolation over the preset's Yeoh law (finite strains where there is material, small
strains in the void); ν = 0.45 (the preset's) and ``formulation=auto``, which
takes the mixed formulation there (Q1/P0 on these quadrilaterals) against volumetric locking.
Structured quadrilaterals of 0.4 mm (100 x 50), Darcy penetration depth Δs = 1 mm, filter
radius 1.6 mm, volume fraction 0.2.  Load 10 kPa: p/E1 = 1.1e-2, 34 times the pa-gripper's.

Its chain (``pacto run gripper-silicone --show-chain``)::

    Embed                x -> rho
    HelmholtzFilter      rho -> rho_tilde
    HeavisideProjection  rho_tilde -> rho_proj
    FixPassive           rho_proj -> rho_bar
    DarcyPressure        rho_bar -> p
    Mechanics            rho_bar, p -> u
    LinearFunctional     u -> delta
    StrainEnergy         u, rho_bar, p -> se
    MechanismRatio       delta, se -> objective
    Volume               rho_bar -> volume
    objective: objective; constraints (<= 0): volume; reported: delta, se
"""
from __future__ import annotations

import sys

from pacto_ng import Case, domain_size, Parameters, Setup
from pacto_ng.geometries import pa_mechanism as geo

WIDTH, HEIGHT = 0.04, 0.02


def _geometry(p: Parameters):
    L, H = domain_size(p, WIDTH, HEIGHT)
    return geo.layout(L, H, gripper=True, output_edge=0.04 * H)


def _setup(p: Parameters) -> Setup:
    return geo.gripper_setup(p, WIDTH, HEIGHT, output_edge=True)


CASE = Case(
    name="gripper-silicone",
    summary="pa-gripper in Dragon Skin 30, mm scale, 10 kPa follower pressure: the jaw closes",
    source="pa-gripper (thesis §6.2) at real scale; the preset's source in presets.py",
    defaults=Parameters(model="wang", material="dragonskin-30", nelx=100, nely=50,
                        plane="strain", thickness=0.01, volfrac=0.2,
                        filter="helmholtz", filter_radius=0.0016, penal=3.0, penal_start=1.0,
                        penal_step=0.04, beta=1.0, beta_max=32.0, beta_every=15,
                        delta_s=0.001, load=1e4, k_out=900.0, load_type="follower",
                        iterations=160, move=0.05, tol=0.01, obj_tol=1e-3),
    geometry=_geometry,
    setup=_setup,
    load_unit="Pa",
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
