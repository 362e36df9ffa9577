"""Report script behind the figures quoted in the issue notes; run from the repository root
with PYTHONPATH=. .venv/bin/python bench/reports/unit_convergence.py."""
import numpy as np, time
from snapmorph.units import UnitGeometry, simulate_unit
from snapmorph.units.geometry import DEFAULT_NODES
cases=[UnitGeometry(L=0.1,h=0.02,t=0.5e-3,w=5e-3,b=5e-3),UnitGeometry(L=0.1,h=0.04,t=0.75e-3,w=5e-3,b=5e-3),
       UnitGeometry(L=0.1,h=0.01,t=0.5e-3,w=5e-3,b=5e-3),
       UnitGeometry(L=0.1,h=0.05,t=1.25e-3,w=10e-3,b=0), UnitGeometry(L=0.1,h=0.03,t=0.25e-3,w=2e-3,b=0),
       UnitGeometry(L=0.1,h=0.005,t=0.25e-3,w=2e-3,b=0), UnitGeometry(L=0.1,h=0.01,t=1.25e-3,w=5e-3,b=0)]
print("| h/L | t/L | w/L | b/L | F_cr rel. diff | S/L diff | theta diff (deg) |")
print("|---|---|---|---|---|---|---|")
for g in cases:
    a=simulate_unit(g,check_self_standing=False); f=simulate_unit(g,nodes=4*DEFAULT_NODES,check_self_standing=False)
    print("| %.2f | %.4f | %.2f | %.2f | %+.3f %% | %+.5f | %+.3f |"%(g.h/g.L,g.t/g.L,g.w/g.L,g.b/g.L,100*(a.F_cr/f.F_cr-1),(a.S-f.S)/g.L,a.theta_deg-f.theta_deg))
g=UnitGeometry(L=0.0995,h=0.01924,t=0.5e-3,w=5e-3,b=5e-3)
e=simulate_unit(g,check_self_standing=False)
from snapmorph.units.geometry import build_unit
k0=build_unit(g,tie="spring").structure._spring_params[0][0]
for k in [None, 10*k0, 100*k0]:
    s=simulate_unit(g,tie="spring",tie_stiffness=k,check_self_standing=False)
    print("spring k=%s: F_cr %+.4f %%, S/L %+.2e, theta %+.4f deg vs exact ties"%("default %.3g N/m"%k0 if k is None else "%.3g"%k,100*(s.F_cr/e.F_cr-1),(s.S-e.S)/g.L,s.theta_deg-e.theta_deg))
d=simulate_unit(g,method="displacement",steps=150,check_self_standing=False)
print("displacement vs mgdc: F_cr %+.4f %%, d_second %+.2e m, theta %+.2e"%(100*(d.F_cr/e.F_cr-1), d.d_second-e.d_second, d.theta_deg-e.theta_deg))
rng=np.random.default_rng(7); L=0.1; st={}; tmax=0
t0=time.perf_counter()
for _ in range(200):
    w=rng.uniform(0.02,0.1)*L
    g=UnitGeometry(L=L,h=rng.uniform(0.05,0.5)*L,t=rng.uniform(0.0025,0.0125)*L,w=w,b=float(rng.choice([0.0,w])))
    t1=time.perf_counter(); r=simulate_unit(g,check_self_standing=False); tmax=max(tmax,time.perf_counter()-t1)
    k=r.status.split(":")[0]; st[k]=st.get(k,0)+1
print("sweep 200:", st, "max time %.3f s, total %.1f s"%(tmax, time.perf_counter()-t0))
