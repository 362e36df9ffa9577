"""3-D strips with known answers (`solver.Structure3D`).

- `cantilever`: a straight strip along x clamped exactly at node 0 (tip deflection
  P L^3 / (3 EI) about either axis for a small tip load);
- `ltb_cantilever`: the same strip thin along y and loaded at the tip in its stiff
  direction z, which buckles laterally: P_cr L^2 / sqrt(EI1 GJ) = 4.013 (Prandtl, Michell)
  for EI2 -> infinity; with the strip's finite EI2 the classical correction divides it by
  sqrt((1 - EI1/EI2)(1 - GJ/EI2)).
"""

import numpy as np

from snapmorph.solver import Structure3D

E, NU = 2.2e9, 0.38


def cantilever(n, L=0.1, w=5e-3, t=0.5e-3, normal=(0.0, 0.0, 1.0)):
    """The strip of ``n`` nodes along x, face normal ``normal`` (its thickness direction),
    clamped at node 0. Returns (structure, rod)."""
    x = np.linspace(0.0, L, n)
    st = Structure3D()
    rod = st.add_rod(np.stack([x, 0 * x, 0 * x], 1), width=w, thickness=t, E=E, nu=NU,
                     normal=normal)
    st.clamp(rod.nodes[0], toward=rod.nodes[1])
    return st, rod


def ltb_cantilever(n, L=0.1, t=0.5e-3, w=10e-3):
    """The lateral–torsional buckling cantilever: (structure, rod, EI1, EI2, GJ)."""
    st, rod = cantilever(n, L, w, t, normal=(0.0, 1.0, 0.0))  # thin along y: z is stiff
    r = st.rods[0]
    return st, rod, float(r.EI1[0]), float(r.EI2[0]), float(r.GJ[0])
