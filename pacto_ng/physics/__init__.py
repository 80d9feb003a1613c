"""Physics: materials as energies, loads, Newton, the mechanics and Darcy blocks."""
