"""The FE model of a deck: dofs, element kinematics, materials per cell, loads and supports."""
