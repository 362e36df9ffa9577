"""Figures of the 3-D unit and the 2-D unit (issue 14).

- `plot_unit3d_states`: the 3-D unit's states (i)-(iii) in perspective, the planar model's
  shapes and both force-displacement curves beside them;
- `plot_knockdown`: F_cr / F_cr(no tilt) against the arch's tilt, one line per h;
- `plot_unit2d_states`: the 2-D unit's two stable states in perspective and its curve;
- `study(out)`: runs the simulations and writes the three figures (`python -m
  snapmorph.figures_unit3d OUT`); `make(out, args)` is the `snapmorph figures --only unit3d`
  group.
Lengths are drawn in millimetres.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STATES = {"i": ("C3", "(i) F = F_cr"), "ii": ("C1", "(ii) unstable, F = 0"),
          "iii": ("C2", "(iii) second stable")}


def _draw_rods(ax, rods, color, lw=1.0, alpha=1.0):
    for name, p in rods.items():
        p = np.asarray(p) * 1e3
        width = 1.6 * lw if name.startswith(("arch", "rail")) or name in (
            "south", "east", "north", "west") else 0.6 * lw
        ax.plot(p[:, 0], p[:, 1], p[:, 2], color=color, lw=width, alpha=alpha)


def _equal_3d(ax, pts):
    """Axes limits around ``pts`` (m) with one scale on all three axes (mm)."""
    pts = np.concatenate([np.asarray(p).reshape(-1, 3) for p in pts]) * 1e3
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.03 * float(np.max(hi - lo))
    lo, hi = lo - pad, hi + pad
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_zlim(lo[2], hi[2])
    ax.set_box_aspect(tuple(hi - lo))
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")


def plot_unit3d_states(r, path, planar=None):
    """States (i)-(iii) of a `units.unit3d.Unit3DResult` in perspective (stress-free state in
    grey), the planar `UnitResult` ``planar`` (optional) beside them in x–z, and the curves."""
    fig = plt.figure(figsize=(15, 8.5))
    ref = r.reference.get("rods", {})
    every = [np.concatenate(list(ref.values()))] if ref else []
    for s in STATES:
        if s in r.shapes:
            every.append(np.concatenate(list(r.shapes[s]["rods"].values())))
    for k, (s, (color, label)) in enumerate(STATES.items()):
        ax = fig.add_subplot(2, 3, k + 1, projection="3d")
        if ref:
            _draw_rods(ax, ref, "0.75", lw=0.8)
        if s in r.shapes:
            _draw_rods(ax, r.shapes[s]["rods"], color)
            extra = (f"\narch tilt {r.arch_tilt_deg.get(s, np.nan):.2f} deg, rail twist "
                     f"{r.rail_twist_deg.get(s, np.nan):.2f} deg")
        else:
            extra = "\n(not reached)"
        ax.set_title(f"3-D {label}{extra}", fontsize=9)
        if every:
            _equal_3d(ax, every)
        ax.view_init(elev=22, azim=-60)

    ax = fig.add_subplot(2, 3, 4)
    for s, (color, label) in STATES.items():
        if s in r.shapes:
            b, a = r.shapes[s]["base"] * 1e3, r.shapes[s]["arch"] * 1e3
            ax.plot(b[:, 0], b[:, 2], "-", color=color, lw=1.6, label=f"3-D {label}")
            ax.plot(a[:, 0], a[:, 2], "-", color=color, lw=0.9)
        if planar is not None and s in getattr(planar, "shapes", {}):
            b, a = planar.shapes[s]["base"] * 1e3, planar.shapes[s]["arch"] * 1e3
            ax.plot(b[:, 0], b[:, 1], "k:", lw=1.2, label="planar model" if s == "i" else None)
            ax.plot(a[:, 0], a[:, 1], "k:", lw=0.8)
    rel = getattr(r, "released", {}) or {}
    if "base_shape" in rel:  # the unit as used: actuator removed, standing on its ends
        b = np.asarray(rel["base_shape"]) * 1e3
        ax.plot(b[:, 0], b[:, 2], "--", color="C4", lw=1.4, label="3-D released (iii)")
        if "arch" in rel:
            a = np.asarray(rel["arch"]) * 1e3
            ax.plot(a[:, 0], a[:, 2], "--", color="C4", lw=0.8)
    ax.set_aspect("equal")
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("z (mm)")
    ax.set_title("side view: 3-D (colour, mean of the rails) and planar (dotted)", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.3), ncol=2)

    ax = fig.add_subplot(2, 3, 5)
    d, F = r.curve
    ax.plot(np.asarray(d) * 1e3, F, "k-", lw=1.5, label="3-D")
    if planar is not None:
        ax.plot(planar.curve[0] * 1e3, planar.curve[1], "C0--", lw=1.2, label="planar")
    for s, (color, _) in STATES.items():
        x = {"i": r.d_cr, "ii": r.d_unstable, "iii": r.d_second}[s]
        y = r.F_cr if s == "i" else 0.0
        if x == x:
            ax.plot(x * 1e3, y, "o", color=color)
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_xlabel("apex displacement d (mm)")
    ax.set_ylabel("force F (N)")
    ax.legend(fontsize=8)

    ax = fig.add_subplot(2, 3, 6)
    ax.axis("off")
    g = r.geometry
    lines = [f"L = {g.L * 1e3:g} mm, h = {g.h * 1e3:g} mm, t = {g.t * 1e3:g} mm, "
             f"w = {g.w * 1e3:g} mm, b = {g.b * 1e3:g} mm",
             "imperfection: " + ", ".join(f"{k} = {v:g}" for k, v in r.imperfection.items()),
             "", f"{'':<10}{'3-D':>10}{'planar':>10}"]

    def row(name, a, b, scale=1.0, fmt="{:.4g}"):
        bb = fmt.format(b * scale) if b is not None and b == b else "-"
        aa = fmt.format(a * scale) if a == a else "-"
        lines.append(f"{name:<10}{aa:>10}{bb:>10}")

    p = planar
    row("F_cr (N)", r.F_cr, p.F_cr if p else None)
    row("d_cr (mm)", r.d_cr, p.d_cr if p else None, 1e3)
    row("d_ii (mm)", r.d_unstable, p.d_unstable if p else None, 1e3)
    row("d_iii (mm)", r.d_second, p.d_second if p else None, 1e3)
    row("S (mm)", r.S, p.S if p else None, 1e3)
    row("theta (deg)", r.theta_deg, p.theta_deg if p else None)
    row("S rel (mm)", getattr(r, "S_released", np.nan),
        getattr(p, "S_released", None) if p else None, 1e3)
    row("th rel (deg)", getattr(r, "theta_released_deg", np.nan),
        getattr(p, "theta_released_deg", None) if p else None)
    lines.append("(rel: released, actuator removed)")
    ax.text(0.0, 1.0, "\n".join(lines), family="monospace", fontsize=9, va="top")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_knockdown(rows, path, paper_note=True):
    """F_cr / F_cr(tilt 0) against tilt (degrees), one line per h. ``rows``: dicts with
    keys h (m), tilt_deg, F_cr (N)."""
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    hs = sorted({row["h"] for row in rows})
    for k, h in enumerate(hs):
        sel = sorted((row for row in rows if row["h"] == h), key=lambda row: row["tilt_deg"])
        base = [row["F_cr"] for row in sel if row["tilt_deg"] == 0.0]
        if not base:
            continue
        x = [row["tilt_deg"] for row in sel]
        y = [row["F_cr"] / base[0] for row in sel]
        ax.plot(x, y, "o-", color=f"C{k}", label=f"h = {h * 1e3:g} mm")
    ax.axhline(1.0, color="0.6", lw=0.8)
    ax.set_xlabel("arch tilt about the base axis (deg)")
    ax.set_ylabel("F_cr / F_cr(no tilt)")
    if paper_note:
        ax.set_title("3-D unit: knock-down of F_cr by a tilted arch\n(paper: experiments fall "
                     "furthest below the model at h = 40 mm)", fontsize=9)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_unit2d_states(r, path):
    """The 2-D unit's stress-free state, second stable state (iii) actuated and released in
    perspective, and its force-displacement curve (`units.unit2d.Unit2DResult`)."""
    fig = plt.figure(figsize=(20, 4.8))
    shapes, edges = dict(r.shapes), dict(r.edges)
    rel = getattr(r, "released", {}) or {}
    if "shapes" in rel:  # the unit as used: actuator and supports removed
        shapes["released"], edges["released"] = rel["shapes"], rel.get("edges", {})
    every = [np.concatenate(list(shapes[s]["rods"].values())) for s in shapes]
    panels = [("0", "0.3", "first stable state (as made)"),
              ("iii", "C2", "second stable state (iii), actuated"),
              ("released", "C4", "second stable state, released")]
    for k, (s, color, title) in enumerate(panels):
        ax = fig.add_subplot(1, 4, k + 1, projection="3d")
        if s in shapes:
            if s != "0":
                _draw_rods(ax, shapes["0"]["rods"], "0.8", lw=0.7)
            _draw_rods(ax, shapes[s]["rods"], color)
            if s in edges and s != "0":
                e = edges[s]
                title += "\n" + ", ".join(f"{n[0].upper()}: {e[n]['theta_deg']:.1f} deg"
                                          for n in ("south", "east", "north", "west"))
        else:
            title += ("\n(not reached: not bistable)" if not r.bistable
                      else "\n(not computed)")
        ax.set_title(title, fontsize=9)
        _equal_3d(ax, every)
        ax.view_init(elev=25, azim=-55)
    ax = fig.add_subplot(1, 4, 4)
    d, F = r.curve
    ax.plot(np.asarray(d) * 1e3, F, "k-")
    ax.axhline(0, color="0.6", lw=0.8)
    ax.set_xlabel("apex displacement d (mm)")
    ax.set_ylabel("force F (N)")
    g = r.geometry
    ax.set_title(f"2-D unit L = {g.L * 1e3:g}, h = {g.h * 1e3:g}, t = {g.t * 1e3:g}, "
                 f"w = {g.w * 1e3:g} mm: {'bistable' if r.bistable else r.status}", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def make(out, args=None):
    """The `snapmorph figures` group "unit3d": write unit3d_states.png, unit3d_knockdown.png
    and unit2d_states.png into ``out``; returns their paths."""
    import os

    study(out)
    return [os.path.join(out, f) for f in ("unit3d_states.png", "unit3d_knockdown.png",
                                           "unit2d_states.png")]


def study(out, tilts=(0.0, 1.0, 2.0, 5.0), heights_mm=(20.0, 40.0), nodes=None):
    """Run the simulations and write unit3d_states.png, unit3d_knockdown.png and
    unit2d_states.png into ``out``. Returns the rows of the knock-down study."""
    import os

    from snapmorph.units import simulate_unit
    from snapmorph.units.frame3d import UnitGeometry
    from snapmorph.units.unit2d import simulate_unit_2d
    from snapmorph.units.unit3d import simulate_unit_3d

    os.makedirs(out, exist_ok=True)
    g = UnitGeometry(L=0.1, h=0.02, t=0.5e-3, w=5e-3, b=5e-3)
    plot_unit3d_states(simulate_unit_3d(g, nodes=nodes), os.path.join(out, "unit3d_states.png"),
                       planar=simulate_unit(g))
    rows = []
    for h in heights_mm:
        gh = UnitGeometry(L=0.1, h=h * 1e-3, t=0.5e-3, w=5e-3, b=5e-3)
        for tilt in tilts:
            r = simulate_unit_3d(gh, nodes=nodes, tilt_deg=tilt)
            rows.append({"h": gh.h, "tilt_deg": tilt, "F_cr": r.F_cr, "theta_deg": r.theta_deg,
                         "S": r.S, "status": r.status})
    plot_knockdown(rows, os.path.join(out, "unit3d_knockdown.png"))
    plot_unit2d_states(simulate_unit_2d(UnitGeometry(L=0.1, h=0.04, t=0.5e-3, w=5e-3)),
                       os.path.join(out, "unit2d_states.png"))
    return rows


if __name__ == "__main__":  # pragma: no cover
    import sys

    for row in study(sys.argv[1] if len(sys.argv) > 1 else "figures"):
        print(row)
