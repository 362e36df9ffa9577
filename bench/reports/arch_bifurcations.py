"""Report script behind the figures quoted in the issue notes; run from the repository root
with PYTHONPATH=. .venv/bin/python bench/reports/arch_bifurcations.py."""
import numpy as np
from solver import reference_models
from solver.stability import seed_imperfection, eigenmodes
T=0.5e-3; l=0.1
def fpk(f):
    i=1
    while i<len(f)-1 and f[i+1]>=f[i]: i+=1
    return i
for ht in [6,10,20]:
    h=ht*T
    for cc in [True, False]:
        st,mid,EI=reference_models.clamped_arch(h, centre_clamped=cc)
        unit=EI*h/l**3
        pf=st.push(mid,(0,-1),2.2*h,method="mgdc",branch="follow")
        pp=st.push(mid,(0,-1),2.2*h,method="displacement",branch="primary")
        ff=pf.force/unit; fp=pp.force/unit
        bif=[ (c.d/h, c.F/unit) for c in pf.bifurcations]
        print("h/t=%d centre %s: followed Fmax %.1f Fmin %.1f | primary Fmax %.1f Fmin %.1f | bifurcations (d/h,F) %s"%(ht,"clamped" if cc else "free",ff[fpk(ff)],ff.min(),fp[fpk(fp)],fp.min(),[("%.3f"%a,"%.0f"%b) for a,b in bif[:2]]))
