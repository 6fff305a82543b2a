#!/usr/bin/env python3
"""The display-vs-box interval widths of `metamer lab` runs, and a model of their session-to-session
spread (docs/benchmarks.md, "The display-vs-box width against the spots' readings").

    python3 benches/lab_width_model.py patches RUN...   each patch's ΔE*ab, interval width, counts,
                                                        each side's standard uncertainty along the
                                                        difference and the width's multiplier of it
    python3 benches/lab_width_model.py model RUN         RUN read with pooled figures (its one-reading
                                                        uncertainties taken as the truth): the fixed
                                                        plan's median width drawn 3000 times (own
                                                        scatter, 5 and 3 readings, Welch-Satterthwaite
                                                        t) against pooled plans of n_box + n_display
                                                        readings (t at the pooled nu)

A RUN is a lab folder (its validation/comparisons.json). The t quantile is the Cornish-Fisher
expansion (Abramowitz and Stegun 26.7.5), within 1e-3 of the table for nu >= 2.
"""
import math, random, statistics as st, sys, json
def lab(xyz, w):
    f=lambda t: t**(1/3) if t>(6/29)**3 else t/(3*(6/29)**2)+4/29
    fx,fy,fz=[f(xyz[i]/w[i]) for i in range(3)]
    return [116*fy-16,500*(fx-fy),200*(fy-fz)]
def jac(xyz,w):
    J=[[0]*3 for _ in range(3)]
    for k in range(3):
        h=1e-6*max(abs(xyz[k]),1e-6)
        up=list(xyz);dn=list(xyz);up[k]+=h;dn[k]-=h
        a,b=lab(up,w),lab(dn,w)
        for i in range(3): J[i][k]=(a[i]-b[i])/(2*h)
    return J
def along(c,xyz,w,u):
    J=jac(xyz,w)
    g=[sum(u[i]*J[i][k] for i in range(3)) for k in range(3)]
    return sum(g[k]*c[k][l]*g[l] for k in range(3) for l in range(3))
def load(run, comp='display_vs_box'):
    d=json.load(open(run+'/validation/comparisons.json'))
    return d[comp], d['white']
def rows(run, comp='display_vs_box'):
    c,w=load(run,comp)
    out={}
    for p in c['patches']:
        r,t=p['reference'],p['test']
        lr,lt=r['lab'],t['lab']
        d=[lt[i]-lr[i] for i in range(3)];de=math.sqrt(sum(x*x for x in d)) or 1
        u=[x/de for x in d]
        vr=along(r['cov_xyz'],r['xyz'],w,u); vt=along(t['cov_xyz'],t['xyz'],w,u)
        iv=p['de76_interval']; half=(iv['hi']-iv['lo'])/2
        out[p['patch']]=dict(de=p['de76'],lo=iv['lo'],hi=iv['hi'],width=iv['hi']-iv['lo'],nb=r['n'],nd=t['n'],
            sdb=math.sqrt(vr),sdd=math.sqrt(vt),mult=half/math.sqrt(vr+vt) if vr+vt>0 else float('nan'),jnd=p['jnd'])
    return out
# t quantile 0.975 by bisection on a series-free approach: use Hill's approximation
def t975(nu):
    if nu>1e6: return 1.959964
    z=1.959964; g1=(z**3+z)/4; g2=(5*z**5+16*z**3+3*z)/96; g3=(3*z**7+19*z**5+17*z**3-15*z)/384; g4=(79*z**9+776*z**7+1482*z**5-1920*z**3-945*z)/92160
    return z+g1/nu+g2/nu**2+g3/nu**3+g4/nu**4
def chi2(k): return sum(random.gauss(0,1)**2 for _ in range(k))
def session(P, plan):
    widths=[]
    if plan=='fixed':
        for de,sb,sd in P:
            vb=sb*sb*chi2(4)/4/5; vd=sd*sd*chi2(2)/2/3
            v=vb+vd; nu=v*v/(vb*vb/4+vd*vd/2)
            h=t975(nu)*math.sqrt(v)
            widths.append(de+h-max(de-h,0))
    else:
        nb,nd,c=plan
        # pooled scale over 24 patches, dof 3*sum(k-1) per side
        nub=3*24*(nb-1); nud=3*24*(nd-1)
        kb=chi2(nub)/nub; kd=chi2(nud)/nud
        for de,sb,sd in P:
            vb=sb*sb*kb/nb; vd=sd*sd*kd/nd; v=vb+vd
            nu=v*v/(vb*vb/nub+vd*vd/nud)
            h=(c if c else t975(nu))*math.sqrt(v)
            widths.append(de+h-max(de-h,0))
    return st.median(widths), widths
def patches(run):
    R=rows(run)
    return [(v['de'], v['sdb']*math.sqrt(v['nb']), v['sdd']*math.sqrt(v['nd'])) for v in R.values()]

def model(run):
    random.seed(1)
    P=patches(run)
    N=3000
    F=[session(P,'fixed')[0] for _ in range(N)]
    print('fixed median width: mean %.3f, 5%%..95%% %.3f..%.3f'%(st.mean(F),sorted(F)[N//20],sorted(F)[-N//20]))
    for plan in [(2,2,None),(3,2,None),(2,3,None),(4,2,None),(3,3,None)]:
        A=[session(P,plan)[0] for _ in range(N)]
        ratios=[a/f for a,f in zip(A,F)]
        print('%d + %d pooled: mean width %.3f, ratio mean %.3f, P(ratio <= 1.1) %.2f'%(plan[0],plan[1],st.mean(A),st.mean(ratios),sum(r<=1.1 for r in ratios)/N))

def table(runs):
    R=[rows(r) for r in runs]
    print('patch', ' | '.join(f'{r.rstrip("/").split("/")[-1]}: de width nb nd sd_b sd_d mult' for r in runs))
    for k in sorted(R[0]):
        print(k, ' | '.join(f"{x[k]['de']:.2f} {x[k]['width']:.3f} {x[k]['nb']} {x[k]['nd']} {x[k]['sdb']:.3f} {x[k]['sdd']:.3f} {x[k]['mult']:.2f} {x[k]['jnd'][:2]}" for x in R))
    for r,x in zip(runs,R):
        print(r, 'median width %.3f'%st.median(v['width'] for v in x.values()), 'median mult %.2f'%st.median(v['mult'] for v in x.values()),
              'median sd_comb %.3f'%st.median(math.hypot(v['sdb'],v['sdd']) for v in x.values()))

if __name__=='__main__':
    if len(sys.argv) < 3 or sys.argv[1] not in ('patches','model'):
        sys.exit(__doc__)
    if sys.argv[1]=='model':
        model(sys.argv[2])
    else:
        table(sys.argv[2:])
