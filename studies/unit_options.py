"""Figures and tables of the unit's fabrication options (issue 11): the actuator joint
(`UnitGeometry.joint_length`) and the bond (`UnitGeometry.bond_length`).

    .venv/bin/python -m studies.unit_options [OUT]   # OUT (default figures/): the figures below

    from studies.unit_options import make, joint_table, bond_sweep
    make("figures")      # figures/unit_bond_length_h10.png, unit_joint_models.png, unit_options.md

- `bond_sweep`: the two h = 10 mm specimens of Table 1 (the paper's model says monostable,
  this project's bistable) with glued lengths from the whole flat part b + w = 10 mm down to
  1 mm: F-d curves, and whether the unit is bistable (and self-standing).
- `joint_table`: F_cr, snap-through, theta of the six Table 1 specimens with the default
  1/8 in joint and with a point clamp (joint_length = 0).
"""

from __future__ import annotations

from pathlib import Path

MM = 1e-3
#: Table 1: (nominal h mm, t mm) -> (average h mm, average L mm)
TABLE1 = {(10, 0.50): (9.11, 99.2), (10, 0.75): (9.10, 99.0), (20, 0.50): (19.24, 99.5),
          (20, 0.75): (19.96, 99.7), (40, 0.50): (40.68, 99.4), (40, 0.75): (39.85, 99.5)}
BONDS_MM = (10.0, 6.0, 4.0, 2.0, 1.0)
W_MM = 5.0


def specimen(hn, t, **kw):
    """The Table 1 specimen (nominal h mm, t mm) as a UnitGeometry (b = w = 5 mm)."""
    from snapmorph.units import UnitGeometry

    h, L = TABLE1[hn, t]
    return UnitGeometry(L=L * MM, h=h * MM, t=t * MM, w=W_MM * MM, b=W_MM * MM, **kw)


def bond_sweep(bonds_mm=BONDS_MM, thicknesses=(0.50, 0.75)) -> dict:
    """{(t mm, bond mm): UnitResult} of the h = 10 mm specimens."""
    from snapmorph.units import simulate_unit

    return {(t, bd): simulate_unit(specimen(10, t, bond_length=bd * MM))
            for t in thicknesses for bd in bonds_mm}


def joint_results() -> dict:
    """{(nominal h, t, joint mm): UnitResult} for the Table 1 specimens, joint 3.175 and 0."""
    from snapmorph.units import simulate_unit

    return {(hn, t, j): simulate_unit(specimen(hn, t, joint_length=j * MM))
            for (hn, t) in TABLE1 for j in (3.175, 0.0)}


def _f(x, fmt=".4g"):
    return "n/a" if x != x else format(x, fmt)


def joint_table(results=None) -> str:
    """Markdown: F_cr and the snapped state of the Table 1 specimens, both joint models."""
    results = results or joint_results()
    lines = ["| h nominal (mm) | t (mm) | joint (mm) | status | F_cr (N) | d_cr (mm) | "
             "bifurcation before F_cr | theta held (deg) | theta released (deg) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (hn, t, j), r in results.items():
        lines.append(f"| {hn} | {t:.2f} | {j:g} | {r.status.split(':')[0]} | {_f(r.F_cr)} | "
                     f"{_f(r.d_cr / MM)} | {r.bifurcation} | {_f(r.theta_deg, '.2f')} | "
                     f"{_f(r.theta_released_deg, '.2f')} |")
    return "\n".join(lines)


def bond_table(sweep) -> str:
    lines = ["| t (mm) | bond (mm) | status | F_cr (N) | min F after the peak (N) | bistable | "
             "self-standing | theta held (deg) | theta released (deg) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for (t, bd), r in sweep.items():
        d, F = r.curve
        import numpy as np

        fmin = float(np.min(F[np.argmax(F):])) if len(F) else float("nan")
        lines.append(f"| {t:.2f} | {bd:g} | {r.status.split(':')[0]} | {_f(r.F_cr)} | "
                     f"{_f(fmin)} | {r.bistable} | {r.self_standing} | "
                     f"{_f(r.theta_deg, '.2f')} | {_f(r.theta_released_deg, '.2f')} |")
    return "\n".join(lines)


def plot_bond_sweep(sweep, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ts = sorted({t for t, _ in sweep})
    fig, axes = plt.subplots(1, len(ts), figsize=(5 * len(ts), 3.8), squeeze=False)
    for ax, t in zip(axes[0], ts):
        for (tt, bd), r in sweep.items():
            if tt != t:
                continue
            d, F = r.curve
            tag = "bistable" if r.bistable else r.status.split(":")[0]
            ax.plot(d / MM, F, lw=1.2, label=f"bond {bd:g} mm: {tag}")
        ax.axhline(0, color="k", lw=0.6)
        ax.set_xlabel("apex displacement d (mm)")
        ax.set_ylabel("F (N)")
        h, L = TABLE1[10, t]
        ax.set_title(f"h = {h} mm, L = {L} mm, t = {t} mm, b = w = 5 mm", fontsize=9)
        ax.legend(fontsize=7)
    fig.suptitle("Glued length at each end vs bistability (Table 1, h = 10 mm)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def plot_joints(results, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 3.8))
    for ax, hn in zip(axes, (10, 20, 40)):
        for (h, t, j), r in results.items():
            if h != hn:
                continue
            d, F = r.curve
            ax.plot(d / MM, F, ls="-" if j else "--", lw=1.1,
                    label=f"t {t} mm, joint {'1/8 in' if j else 'point clamp'}")
        ax.axhline(0, color="k", lw=0.6)
        ax.set_title(f"h nominal {hn} mm", fontsize=9)
        ax.set_xlabel("d (mm)")
        ax.set_ylabel("F (N)")
        ax.legend(fontsize=6)
    fig.suptitle("Actuator joint: glued 1/8 in stem vs point clamp (Table 1 specimens)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def make(out, args=None) -> list:
    """Write the figures and a Markdown page of the tables into ``out``; return the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    sweep = bond_sweep()
    joints = joint_results()
    paths = [plot_bond_sweep(sweep, out / "unit_bond_length_h10.png"),
             plot_joints(joints, out / "unit_joint_models.png")]
    md = out / "unit_options.md"
    md.write_text("# Unit options: bond length and actuator joint\n\n"
                  "## Bond length at h = 10 mm\n\n" + bond_table(sweep) + "\n\n"
                  "![bond](unit_bond_length_h10.png)\n\n## Joint models\n\n"
                  + joint_table(joints) + "\n\n![joints](unit_joint_models.png)\n")
    paths.append(md)
    return paths


if __name__ == "__main__":  # pragma: no cover
    import sys

    for written in make(sys.argv[1] if len(sys.argv) > 1 else "figures"):
        print(f"wrote {written}")
