"""Domains of the cases: each module's ``layout(...)`` returns a :class:`pacto_ng.mesh.Layout`
with named boundaries ("fixed", "symmetry", "inlet", "zero_pressure", ...), passive regions and
ports."""
