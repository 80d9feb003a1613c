"""Post-analysis of a result (docs/theory.md §7, thesis ch. 6): from a density field to a part.

threshold → polygons (:mod:`.threshold`; the smoothed densities :mod:`.grid`, the boundary
names :mod:`.boundary`, the threshold's choice :mod:`.threshold_choice`) → body-fitted Netgen
mesh with named boundaries (:mod:`.remesh` in 2D, the part's geometry :mod:`.traced` or, on the
case's own shape, :mod:`.domain_part`; :mod:`.part3d` and :mod:`.remesh3d` in 3D; both behind
:func:`.part.make_part`) → the part analysed with the run's own material law under the Darcy,
fixed or follower pressure (:class:`.part_analysis.PartAnalysis`) → STL and VTU
(:mod:`.export`) and pictures (:mod:`.pictures`); ``pacto analyse`` chains it all (:func:`.analyse.analyse_run`; a case's own
geometry as built: :mod:`.as_built`).
"""
from ..physics.walls import outward_normal, pressure_body_force
from .boundary import outer_boundary
from .export import convert, deformation_fields, extrude_solid, write_stl, write_vtu
from .grid import mesh_to_pyvista, nodal_density
from .part import Part, make_part
from .part_analysis import PartAnalysis
from .sweep_result import Sweep, SweepPoint
from .pictures import plot_deformed, plot_sweeps
from .remesh import Remeshed, remesh
from .sampler import pressure_sampler
from .threshold import Component, Loop, Thresholded, threshold
from .traced import build_geometry

__all__ = ["threshold", "nodal_density", "mesh_to_pyvista", "outer_boundary", "Thresholded",
           "Component", "Loop", "remesh", "Remeshed", "build_geometry", "pressure_sampler",
           "make_part", "Part", "PartAnalysis", "Sweep", "SweepPoint", "outward_normal",
           "pressure_body_force", "write_stl", "extrude_solid", "write_vtu",
           "deformation_fields", "convert", "plot_deformed", "plot_sweeps"]
