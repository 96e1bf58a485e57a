"""Post-processing of result files: CSA S474 ductility, plots (matplotlib, the ``plot`` extra),
ParaView export (XDMF via meshio) and the HTML validation report.

Modules import matplotlib only inside the functions that draw, so ``icewall run`` never loads
it.
"""
