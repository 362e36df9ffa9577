"""Report script behind the figures quoted in the issue notes; run from the repository root
with PYTHONPATH=. .venv/bin/python bench/reports/arch_imperfection.py."""
import numpy as np
from solver import reference_models
from solver.stability import seed_imperfection
T=0.5e-3; l=0.1
def fpk(f):
    i=1
    while i<len(f)-1 and f[i+1]>=f[i]: i+=1
    return i
for ht in [6,10,20]:
    h=ht*T
    st,mid,EI=reference_models.clamped_arch(h, centre_clamped=False)
    pf=st.push(mid,(0,-1),2.2*h,method="mgdc")
    mode=pf.bifurcations[0].mode
    imp=seed_imperfection(st, mode, thickness_fraction=1e-4)
    pi=imp.push(mid,(0,-1),2.2*h,method="mgdc")
    f=pi.force/(EI*h/l**3)
    print("h/t=%d free centre, 1e-4 t imperfection in the critical mode: F_max %.1f"%(ht,f[fpk(f)]))
