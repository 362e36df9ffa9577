"""Report script behind the figures quoted in the issue notes; run from the repository root
with PYTHONPATH=. .venv/bin/python bench/reports/arch_bifurcations.py.

The clamped cosine arch (l = 0.1 m, t = 0.5 mm) with its centre clamped and with its centre
rotation free: F_max, F_min in EI h / l^3 on the followed and the primary path, the located
bifurcations, and F_max with a 1e-4 t imperfection in the critical mode.
"""
from snapmorph.solver.stability import seed_imperfection
from validation.arch import clamped_arch, first_peak_index

T, L_SPAN = 0.5e-3, 0.1
for ht in [6, 10, 20]:
    h = ht * T
    for clamped in [True, False]:
        st, mid, EI = clamped_arch(h, centre_clamped=clamped)
        unit = EI * h / L_SPAN**3
        follow = st.push(mid, (0, -1), 2.2 * h, method="mgdc", branch="follow")
        primary = st.push(mid, (0, -1), 2.2 * h, method="displacement", branch="primary")
        ff, fp = follow.force / unit, primary.force / unit
        bif = [("%.3f" % (c.d / h), "%.0f" % (c.F / unit)) for c in follow.bifurcations[:2]]
        line = ("h/t=%d centre %s: followed Fmax %.1f Fmin %.1f | primary Fmax %.1f Fmin %.1f"
                " | bifurcations (d/h, F) %s" % (ht, "clamped" if clamped else "free",
                ff[first_peak_index(ff)], ff.min(), fp[first_peak_index(fp)], fp.min(), bif))
        if follow.bifurcations:
            imp = seed_imperfection(st, follow.bifurcations[0].mode, thickness_fraction=1e-4)
            fi = imp.push(mid, (0, -1), 2.2 * h, method="mgdc").force / unit
            line += " | 1e-4 t imperfection Fmax %.1f" % fi[first_peak_index(fi)]
        print(line)
