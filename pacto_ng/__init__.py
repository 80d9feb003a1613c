"""pacto_ng — NGSolve-based topology optimisation of pressure-actuated soft robots and
compliant mechanisms."""
__version__ = "0.1.0"
