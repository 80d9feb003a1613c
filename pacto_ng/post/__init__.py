"""Post-analysis of a result (docs/theory.md §7, thesis ch. 6): from a density field to a part.

threshold → polygons (:mod:`.threshold`; the smoothed densities :mod:`.grid`, the boundary
names :mod:`.boundary`, the threshold's choice :mod:`.threshold_choice`) → body-fitted Netgen
mesh with named boundaries (:mod:`.remesh`; the part's geometry :mod:`.traced` or, on the case's
own shape, :mod:`.domain_part`) → Neo-Hookean sweeps under fixed, follower and Darcy pressure
(:mod:`.reanalysis`) → STL, VTU and pictures (:mod:`.export`); all of it in one call with
:func:`.report.post_analyse`.
"""
from .boundary import outer_boundary
from .export import (convert, deformation_fields, extrude_solid, plot_deformed, plot_sweeps,
                     write_stl, write_vtu)
from .grid import mesh_to_pyvista, nodal_density
from .reanalysis import (FixedBoundaryPressure, Reanalysis, Sweep, SweepPoint, analyse,
                         follower_pressure_terms, output_ports, outward_sign,
                         pressure_body_force)
from .remesh import Remeshed, pressure_sampler, remesh
from .report import PostResult, post_analyse
from .threshold import Component, Loop, Thresholded, threshold
from .traced import build_geometry

__all__ = ["threshold", "nodal_density", "mesh_to_pyvista", "outer_boundary", "Thresholded",
           "Component", "Loop", "remesh", "Remeshed", "build_geometry", "pressure_sampler",
           "Reanalysis", "analyse", "output_ports", "Sweep", "SweepPoint", "FixedBoundaryPressure",
           "follower_pressure_terms", "outward_sign", "pressure_body_force", "write_stl",
           "extrude_solid", "write_vtu", "deformation_fields", "convert", "plot_deformed",
           "plot_sweeps", "post_analyse", "PostResult"]
