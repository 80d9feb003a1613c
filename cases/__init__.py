"""The cases: one module each, defining ``CASE`` (a :class:`pacto_ng.case.Case`).  Each is also a
script: ``python cases/<name>.py [pacto run options]``."""
