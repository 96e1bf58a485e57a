"""icewall: nonlinear finite-element analysis of steel-concrete-steel composite ice-resisting walls.

Units are N, mm and MPa throughout. The model is that of Link & Elwi (1992), Structural
Engineering Report No. 180, University of Alberta, with the corrections of errata.md.
"""

__version__ = "0.1.0"
