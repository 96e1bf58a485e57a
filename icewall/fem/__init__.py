"""Finite-element kernels, vectorised over elements x Gauss points.

Array conventions (einsum letters used throughout):
  e = element, q = Gauss point, a/b = local node, i/j = strain/stress component,
  k/l = spatial direction (x, y).
Strain and stress are 4-vectors [xx, yy, zz, xy], tension positive, engineering shear strain
gamma_xy. zz is the out-of-plane (plane strain/stress) or hoop (axisymmetric) component.
Global dof numbering: dof = 2 * node + direction (0 = x, 1 = y).
"""
