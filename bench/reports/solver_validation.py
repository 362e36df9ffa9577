"""Report script behind the figures quoted in the issue notes; run from the repository root
with PYTHONPATH=. .venv/bin/python bench/reports/solver_validation.py."""
import numpy as np
from validation.arch import arch_path, first_peak_index as first_peak
from validation.cantilever import cantilever_path, max_relative_errors
from validation.column import column, P_CR, L
errs=[]
for n in [26,51,101,201]:
    p=cantilever_path(n, steps=20)
    e=max_relative_errors(p); errs.append(e[0])
    print("cantilever N=%d: max rel error deflection %.2e, force %.2e"%(n,e[0],e[1]))
ns=np.array([26,51,101,201]); print("slope", np.polyfit(np.log(ns),np.log(errs),1)[0])
p=column().push(100, direction=(-1.0, 0.0), distance=0.03 * L, method="mgdc")
w=(p.displacement>0.005*L)&(p.displacement<0.02*L)
print("column plateau mean/Pcr %.5f range %.5f..%.5f"%(p.force[w].mean()/P_CR, p.force[w].min()/P_CR, p.force[w].max()/P_CR))
for ht in [6,10,20]:
    for m in ["mgdc","displacement"]:
        path,h,unit=arch_path(ht,m)
        f=path.force/unit; i=first_peak(f)
        z=np.where(np.diff(np.sign(f[1:])))[0]+1
        print("arch h/t=%d %s: F_max %.1f at d/h %.3f, F_min %.1f, steps %d, status %s"%(ht,m,f[i],path.displacement[i]/h,f.min(),len(path),path.status))
