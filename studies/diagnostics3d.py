"""Diagnostic variants of the 3-D unit (issue 14): where does the stiff-plate 3-D unit's
residual against the planar model come from? (docs/unit3d.md, "Agreement with the planar
model"; `python -m studies.studies3d theta_residual 41,81`.)

A variant is the mesh of `units.unit3d.build_unit_mesh_3d` changed before it is solved:

- ``bar_factor``: thickness of the end plates' cross bars as a multiple of t, with a free
  strip's torsion (the "stiff" plate before this study was 10); ``bar_modulus``: the bars
  keep the thickness t and their Young's modulus is multiplied instead, which stiffens them
  equally in bending and torsion whatever their width (the shipped ``end_plate="stiff"``
  is 1e4); ``bar_torsion``: "plate" (the shipped bars: a plate strip's G b t^3 / 3) or
  "strip" (a free strip's G J(b, t), which loses torsion as the bars narrow);
- ``joint_bending`` / ``joint_twist``: {kind: scale} multiplying the bending (both axes) or
  twisting stiffness of the rigid joints (`Structure3D.joint` pairs) between rods of the
  given kinds, kind = "arch-centre", "bar-rail", "bar-centre", "bar-bar", "brace", "head";
- ``single_base``: the planar-equivalent base (one rod of width 4w on the end regions and
  2w between, on the centre line) instead of the frame, same arch, bond, rollers, actuator;
- any `build_unit_mesh_3d` option (``bond``, ``brace_width``, ``nu``, ``bar_divisions``).

`Structure3D.joint` couples an edge of each rod by the bending and twisting pair a kink
inside one rod would have (series stiffness of the two half edges), and `Mesh3D.bond` adds
it in both valid orders. A joint is therefore not a constraint: it is as compliant as about
half an edge of the rods it joins, which is the O(1/N) part of the stiff-plate residual
(the arch's moment passes centre strip -> bar -> rail through such pairs). The joint scales
edit the built structure's private pair table (`Structure3D._pairs`): a diagnostic only.
"""

from __future__ import annotations

import time

import numpy as np

from snapmorph.units.frame3d import Mesh3D
from snapmorph.units.shapes import end_tangent_angle

__all__ = ["run_variant", "joint_kind", "VARIANTS", "DECISIVE"]


def _rod_kind(name: str) -> str:
    for key in ("rail", "centre", "bar", "brace", "arch", "base"):
        if name.startswith(key):
            return key
    return "head" if name.startswith("actuator_head") else name


def joint_kind(mesh: Mesh3D, a: int, b: int) -> str:
    """Kind of the joint between nodes a and b: the two rods' kinds sorted, e.g.
    "arch-centre" (the bond), "bar-rail", "bar-centre", "bar-bar", "brace", "head"."""
    ka = _rod_kind(mesh._rod_index(a)[0].name)
    kb = _rod_kind(mesh._rod_index(b)[0].name)
    kinds = {ka, kb}
    if "brace" in kinds:
        return "brace"
    if "head" in kinds:
        return "head"
    if kinds == {"arch", "centre"} or kinds == {"arch", "base"}:
        return "arch-centre"
    order = ("bar", "arch", "rail", "centre")
    return "-".join(sorted((ka, kb), key=order.index))


def _single_base(g, mesh: Mesh3D, model):
    """Replace the frame by the planar-equivalent base rod: one rod on the centre line,
    width 4w over the end regions (edges whose midpoint is inside x0) and 2w between;
    the arch bond, rollers and actuator as in the frame model. Returns (mesh, base nodes,
    arch nodes, push node)."""
    from snapmorph.units.frame3d import Mesh3D as M

    old = mesh
    rail = old.rod("rail_left")
    x = rail.xyz[:, 0].copy()
    L, w, t, x0 = g.L, g.w, g.t, g.flat_length
    mid = 0.5 * (x[1:] + x[:-1])
    # the edge straddling x0 (midpoint at x0 up to round-off) is hollow, 2w, as the rails'
    # edge there (and the planar unit's node past x0); 4w on it moves the solid part's end
    # half an edge into the hollow part: theta -2.1 deg, F_cr +2.5 % at 41 nodes (h = 19 mm)
    tol = 1e-9 * L
    width = np.where((mid < x0 - tol) | (mid > L - x0 + tol), 4 * w, 2 * w)
    new = M(E=old.E, nu=old.nu)
    zeros = np.zeros_like(x)
    base = new.add_rod("base", np.stack([x, zeros, zeros], 1), width, t)
    # copy the arch and the actuator head; renumber their nodes
    remap = {}
    for r in old.rods:
        if r.name == "arch" or r.name.startswith("actuator_head"):
            nodes = new.add_rod(r.name, r.xyz, r.width, r.thickness, r.normal)
            remap.update({int(o): int(n) for o, n in zip(r.nodes, nodes)})
    arch_old = old.rod("arch")
    c_left, c_right = old.rod("centre_left"), old.rod("centre_right")
    n_end = len(c_left.nodes)
    arch = np.array([remap[int(n)] for n in arch_old.nodes])
    # bond: as the frame model (joint at inner bonded nodes, tie at the ends)
    cl = {int(c): k for k, c in enumerate(c_left.nodes)}
    cr = {int(c): len(x) - n_end + k for k, c in enumerate(c_right.nodes)}
    for kind, lst in (("joint", old.joints), ("tie", old.ties)):
        for a, b in lst:
            for p, q in ((a, b), (b, a)):
                if p in remap and (q in cl or q in cr):
                    bn = int(base[cl[q]] if q in cl else base[cr[q]])
                    if kind == "joint":
                        new.joints.append((remap[p], bn) if (p, q) == (a, b) else (bn, remap[p]))
                    else:
                        new.ties.append((remap[p], bn))
                elif p in remap and q in remap and (p, q) == (a, b):
                    (new.joints if kind == "joint" else new.ties).append((remap[a], remap[b]))
    for grp in old.rigid:
        new.rigid.append([remap[int(n)] for n in grp])
    push = remap[int(old.named["push"])]
    new.fixes.append((push, "xy"))
    sup = [int(base[int(np.argmin(np.abs(x - xs)))]) for xs in
           (old.positions[model.supports][:, 0].min(), old.positions[model.supports][:, 0].max())]
    for n in sup:
        new.fixes.append((n, "yz"))  # y: the single rod's roll about x is otherwise free
    new.named.update(h=g.h, push=push)
    return new, base, arch, push


def run_variant(g, nodes=41, bar_factor=None, bar_modulus=None, bar_torsion=None,
                joint_bending=None, joint_twist=None, single_base=False, steps=60,
                push_through=None, **options):
    """Push one variant through; returns a dict of metrics (SI, degrees) and timings.
    ``push_through``: the push driver (default `units.push3d.push_through`)."""
    if push_through is None:
        from snapmorph.units.push3d import push_through
    from snapmorph.units.unit3d import build_unit_mesh_3d, section_rotation_deg

    t0 = time.perf_counter()
    options.setdefault("end_plate", "stiff")
    model = build_unit_mesh_3d(g, nodes=nodes, **options)
    mesh = model.mesh
    for r in mesh.rods:
        if r.name.startswith("bar_"):
            if bar_factor is not None:  # the old "stiff": thicker bars, free-strip torsion
                r.thickness, r.E_factor, r.plate = g.t * float(bar_factor), 1.0, False
            if bar_modulus is not None:
                r.E_factor = float(bar_modulus)
            if bar_torsion is not None:
                r.plate = bar_torsion == "plate"
    rail_l, rail_r, arch, push = model.rail_left, model.rail_right, model.arch, model.push_node
    if single_base:
        mesh, base, arch, push = _single_base(g, mesh, model)
        rail_l = rail_r = base
    st = mesh.to_structure()
    counts = {}
    for key, pair in list(st._pairs.items()):
        if key[0] != "joint":
            continue
        kind = joint_kind(mesh, key[1], key[2])
        counts[kind] = counts.get(kind, 0) + 1
        sb = (joint_bending or {}).get(kind, 1.0)
        stw = (joint_twist or {}).get(kind, 1.0)
        if sb != 1.0 or stw != 1.0:
            p = list(pair)
            p[4] *= sb
            p[5] *= sb
            p[6] *= stw
            st._pairs[key] = tuple(p)
    st._cache = None
    out = push_through(st, push, 3.0 * g.h, steps=steps, critical=False)
    res = dict(status=out.status, F_cr=out.F_cr, d_cr=out.d_cr, d_second=out.d_second,
               joints=counts, n_nodes=mesh.n_nodes, time=time.perf_counter() - t0)
    if "iii" in out.states:
        P = np.asarray(out.states["iii"])
        rl, rr = P[rail_l], P[rail_r]
        base = 0.5 * (rl + rr)
        res["theta"] = end_tangent_angle(base)
        res["S"] = float(base[-1, 0] - base[0, 0])
        res["base"] = base
        res["positions"] = P
        res["arch"] = arch
        if not single_base:
            # (c) how theta is read: the two rails separately, and the centre strips' end
            # edges instead of the rails' (the same angle if the end plates do not warp)
            res["rail_twist"] = float(np.max(np.abs(section_rotation_deg(rl, rr))))
            res["theta_rails"] = (end_tangent_angle(rl), end_tangent_angle(rr))
            cl, cr = P[mesh.groups["centre_left"]], P[mesh.groups["centre_right"]]
            res["theta_centre"] = end_tangent_angle(np.concatenate([cl[:2], cr[-2:]]))
    res["mesh"] = mesh
    return res


#: the variants of the study (`studies.studies3d theta_residual`), in the order printed:
#: name -> `run_variant` options. "bars 10 t thick" = the "stiff" plate before the study;
#: "rigid bars" = bars of thickness t with 1e5 x E (the shipped "stiff" is 1e4 x E).
VARIANTS = {
    "stiff (shipped: bars of 1e4 x E)": {},
    "bars 10 t thick (the old stiff)": {"bar_factor": 10},
    "(a) bars 30 t thick": {"bar_factor": 30},
    "(a) bars 100 t thick": {"bar_factor": 100},
    "(a) rigid bars (t thick, E x 1e5)": {"end_plate": "elastic", "bar_modulus": 1e5},
    "(a) rigid bars + rigid bar joints": {
        "end_plate": "elastic", "bar_modulus": 1e5,
        "joint_bending": {"bar-rail": 1e3, "bar-centre": 1e3},
        "joint_twist": {"bar-rail": 1e3, "bar-centre": 1e3}},
    "(b) single base rod 4w/2w": {"single_base": True},
    "(d) stiff, bond = ties": {"bond": "tie"},
    "(d) stiff, no arch-strip joint bending": {"joint_bending": {"arch-centre": 0.0}},
    "(e) stiff, braces 0.1 mm wide": {"brace_width": 1e-4},
    "(f) stiff, nu = 0": {"nu": 0.0},
    "(f) stiff, nu = 0.5": {"nu": 0.5},
    "(f) rigid bars, nu = 0": {"end_plate": "elastic", "bar_modulus": 1e5, "nu": 0.0},
    "elastic (shipped: bars' torsion G b t^3/3)": {"end_plate": "elastic"},
    "elastic, free-strip bars' torsion": {"end_plate": "elastic", "bar_torsion": "strip"},
}

#: the variants of the convergence study (41/81/161/321 nodes)
DECISIVE = ("stiff (shipped: bars of 1e4 x E)", "bars 10 t thick (the old stiff)", "(a) rigid bars (t thick, E x 1e5)",
            "(a) rigid bars + rigid bar joints", "(b) single base rod 4w/2w")
