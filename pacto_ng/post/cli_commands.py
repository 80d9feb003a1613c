"""``pacto export``: from a finished run to a part to fabricate from (``pacto analyse`` is
:mod:`pacto_ng.post.analyse`, ``pacto compare`` :mod:`pacto_ng.post.compare`; reading a run
folder back, :mod:`pacto_ng.post.runs`).

``export DIR --format stl|vtk|vtu|msh`` makes the part of the run's final design (the settings
of ``DIR/analysis/analysis.json`` when it exists, so that the exported part is the analysed
one) and writes the whole mechanism (mirrored about the symmetry line or planes), in mm for STL
and m otherwise (docs/postprocessing.md, "pacto export").  One flow for 2D and 3D,
:func:`export_run`; only making the part's solid and mirroring and writing it differ by
dimension (:mod:`.export_part`).
"""
from __future__ import annotations

import json
import math

from ..errors import InputError
from .export import UNITS
from .export_part import FORMATS, STEPS, write_msh
from .mirror3d import is_symmetry_name
from .post3d import is_3d
from .runs import export_destination, load_run
from .seal import design_seal, warn_if_open

#: write_msh (the 2D part as Gmsh 2.2) is :mod:`.export_part`'s, named here too
__all__ = ["check_threshold", "check_units", "export_run", "write_msh"]


# ------------------------------------------------------------------------------------------
def check_threshold(value, *, allow_volume: bool = False, name: str = "--threshold"):
    """A threshold in (0, 1), or (with ``allow_volume``) the word ``volume``: the
    volume-preserving threshold of :func:`~pacto_ng.post.threshold_choice.volume_threshold`."""
    if isinstance(value, str):
        if value.strip().lower() == "volume":
            if not allow_volume:
                raise InputError(f"{name}: 'volume' is an option of 'pacto analyse' "
                                 f"--threshold only; give a number in (0, 1)")
            return "volume"
        try:
            value = float(value)
        except ValueError:
            raise InputError(f"{name}: expected a number in (0, 1)"
                             f"{' or volume' if allow_volume else ''}, got '{value}'") from None
    if not (0.0 < float(value) < 1.0) or not math.isfinite(float(value)):
        raise InputError(f"{name}: must lie in (0, 1), got {value:g}")
    return float(value)


def _say(quiet, msg):
    if not quiet:
        print(msg, flush=True)


# ------------------------------------------------------------------------------------------
# pacto export
#: ``pacto export``'s length unit when ``--units`` is not given: the STL (for slicers and CAD,
#: which read it in mm) in mm; the analysis files (vtk, vtu, msh) in the solver's SI metres
DEFAULT_UNITS = {"stl": "mm", "vtk": "m", "vtu": "m", "msh": "m"}


def check_units(units, fmt: str) -> str:
    """``--units``: mm or m (None: :data:`DEFAULT_UNITS` of the format)."""
    if units is None:
        return DEFAULT_UNITS[fmt]
    if units not in UNITS:
        raise InputError(f"--units: choose from {', '.join(UNITS)} (got '{units}')")
    return units


def _analysed_settings(run, threshold_value, maxh, threshold2):
    """The threshold, maxh and threshold2 not given: those of ``DIR/analysis/analysis.json``
    when it exists (the exported part is then the analysed one), else None."""
    prev = run.path / "analysis" / "analysis.json"
    if prev.exists() and (threshold_value is None or maxh is None or threshold2 is None):
        try:
            s = json.loads(prev.read_text())["settings"]
            threshold_value = s["threshold"] if threshold_value is None else threshold_value
            maxh = s["maxh"] if maxh is None else maxh
            threshold2 = s.get("threshold2") if threshold2 is None else threshold2
        except (ValueError, KeyError, TypeError):
            pass
    return threshold_value, maxh, threshold2



def export_run(folder, fmt: str, *, out=None, threshold_value=None, maxh=None,
               quiet: bool = False, threshold2=None, units=None, mirror: bool = True) -> int:
    """``pacto export``: the part of a run as stl | vtk | vtu | msh (msh: 2D runs only).

    Without ``--threshold``/``--maxh``/``--threshold2`` the settings of
    ``DIR/analysis/analysis.json`` are used when it exists (the exported part is then the
    analysed one), else 0.5, half the run's element size and 0.5.  The part's solid
    (:data:`~.export_part.STEPS`, by the run's mesh dimension): 2D the thresholded design
    remeshed (``maxh``); 3D the closed, smoothed iso-surface and the clipped solid (not
    remeshed: ``maxh`` unused).  Its chambers are checked for a seal on the design
    (:func:`~.seal.design_seal`: a warning on stderr when open).

    * ``mirror`` (default): a case solved on a symmetric half or quarter is written whole: the
      part and its mirror images about the straight symmetry line (2D) or the symmetry planes
      (3D, :mod:`.mirror3d`); False: the part as solved.
    * ``units``: ``mm`` or ``m``, default :data:`DEFAULT_UNITS` (mm for STL, m otherwise).
    * STL: binary, closed, the unit in its header; 2D the part extruded by the case's
      thickness (``params.json``), 3D the smoothed surface.  VTK / VTU: the 2D cells, or the
      3D clipped solid, with the run's final state on them (ρ̄, u, p, the model's strain and
      stress; the coordinates and u in ``units``, p and stress in Pa).  MSH (2D): Gmsh 2.2
      with the boundary names as physical groups.
    * A two-material part (ρ̄2 at ``threshold2``) has the regions ``soft`` and ``stiff``: the
      STL is the whole part; the VTK/VTU has cell data ``material`` (named in its field data)
      and ``E``; the MSH the materials as physical groups of the triangles.

    Prints one line: the file, the threshold, the part's measures, the unit, what it was
    mirrored about, the materials and the fields written.
    """
    units, threshold2 = _checked_options(fmt, units, threshold_value, maxh, threshold2)
    run = load_run(folder, "export")
    dim = 3 if is_3d(run) else 2
    if fmt not in FORMATS[dim]:
        raise InputError(f"--format {fmt} is not supported for {dim}D runs yet")
    threshold_value, maxh, threshold2 = _analysed_settings(run, threshold_value, maxh,
                                                           threshold2)
    setup = run.case.make_setup(run.params)
    make, write = STEPS[dim]
    part = make(run, setup, 0.5 if threshold_value is None else float(threshold_value), maxh,
                0.5 if threshold2 is None else float(threshold2))
    warn_if_open(design_seal(part.problem, setup, part.threshold, exclude=part.exclude))
    dst = export_destination(run, out, fmt)
    done = write(dst, fmt, part, run, units, mirror)
    notes = _mirror_notes(done.about, mirror, part.problem.mesh) + done.notes
    _say(quiet, f"{dst}: {run.case.name} part{' (3D)' if dim == 3 else ''}, threshold "
                f"{part.threshold:g}, {done.measures}; units {units}"
                + "".join(f"; {n}" for n in notes))
    return 0


def _checked_options(fmt: str, units, threshold_value, maxh, threshold2) -> tuple:
    """``(units, threshold2)``: the options checked (InputError), the unit defaulted
    (:func:`check_units`) and ``threshold2`` as a number."""
    if fmt not in FORMATS[2]:
        raise InputError(f"--format: choose from {', '.join(FORMATS[2])} (got '{fmt}')")
    units = check_units(units, fmt)
    if threshold_value is not None:
        check_threshold(threshold_value)
    if threshold2 is not None:
        threshold2 = check_threshold(threshold2, name="--threshold2")
    if maxh is not None and not maxh > 0:
        raise InputError(f"--maxh: must be positive, got {maxh:g}")
    return units, threshold2


def _mirror_notes(about, mirror: bool, mesh) -> list:
    """What the part was mirrored about (``about``), or why not, when the run's mesh has a
    symmetry boundary."""
    if about:
        return [f"whole: mirrored about {about}"]
    if not any(map(is_symmetry_name, mesh.GetBoundaries())):
        return []
    return ["not mirrored: the run's symmetry boundary is not a straight line" if mirror
            else "the part as solved (--no-mirror)"]
