"""C-beam — an analysis, not an optimisation (Yoon et al. 2005; Wang et al. 2014 §2; thesis
§5.2.1 and App. C).

A 10 x 10 m square whose C-shaped solid (1 m thick top, bottom and left arms) surrounds void
(E0 = 1e-9 E1); left edge clamped; f1 = 0.002 N downward at the free end of the top arm and
f2 = 0.003 N rightward at the free end of the bottom arm, times a load factor λ that is ramped
until Newton fails or an element inverts.  It shows why the Wang interpolation matters: the
crushed void makes a plain Neo-Hookean model fail early.  Thesis (COMSOL): Neo-Hookean
(0.0009, 0.0099) N, Wang (0.0055, 0.0145) N.  ``--load`` is the largest λ tried.
"""
from __future__ import annotations

import sys

from pacto_ng import Case, Parameters, PointLoad, Setup, Supports
from pacto_ng.geometries import c_beam as geo


def _geometry(p: Parameters):
    return geo.layout(10.0, 1.0)


def _setup(p: Parameters) -> Setup:
    return Setup(supports=Supports(clamp=("fixed",)),
                 loads=(PointLoad("f1", (0.0, -0.002)), PointLoad("f2", (0.003, 0.0))),
                 void=("void",), objective="compliance")


CASE = Case(
    name="c-beam",
    summary="C-beam load-factor sweep until failure (analysis; Neo-Hookean vs Wang)",
    source="Yoon et al. (2005); Wang, Lazarov, Sigmund & Jensen (2014); thesis §5.2.1, App. C",
    defaults=Parameters(model="neohookean", nelx=10, nely=10, maxh=1.0, plane="strain",
                        thickness=1.0, E1=1.0, E0=1e-9, nu=0.3, load=20.0),
    geometry=_geometry,
    setup=_setup,
    load_unit="(load factor on f1, f2)",
    analysis_only=True,
)

if __name__ == "__main__":
    from pacto_ng import main

    sys.exit(main(["run", CASE.name] + sys.argv[1:]))
