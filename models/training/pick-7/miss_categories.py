# Stop 43: where do the things misses arise? Over cascade_dump output (as modes_oracle.py), bad = non-sky
# valid pixels with |full - gt| > 10. Categories by the coarse soft argmax (each coarse pixel over its 4 x 4
# output pixels), the half stage's answer (over 2 x 2) and the coarse distribution's most probable mode.
# Stop 44: with a fourth argument `edges`, also the largest category's error by distance to the truth's
# nearest depth edge (../pick-10/edge_error.py's edge_distance: a jump of more than 20 index units
# between 4-neighbours, longitude wrapping) at the output grid: within 3 and within 8 pixels.
# Usage: miss_categories.py DUMP_DIR A B [edges]   (the venv of ../../../../shared/tools/omni_np.py)
import json, sys
import numpy as np
d=sys.argv[1]; A,B=int(sys.argv[2]),int(sys.argv[3])
EDGES = len(sys.argv) > 4 and sys.argv[4] == "edges"
if EDGES:
    import os
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "../pick-10"))
    from edge_error import edge_distance

C={}
n=0; errall=0.
def add(k,v,e):
    c=C.setdefault(k,[0,0.]); c[0]+=v; c[1]+=e
for f in range(A,B+1):
    meta=json.load(open(f"{d}/{f:05d}.json"))
    r=lambda n: np.fromfile(f"{d}/{f:05d}_{n}.f32",dtype="<f4").reshape(meta[n])
    p=r("coarse_prob"); h=r("coarse_hyp"); gt=r("gt"); v=r("valid"); full=r("full"); co=r("coarse"); ha=r("half")
    rep=lambda a,k: np.repeat(np.repeat(a,k,axis=-2),k,axis=-1)
    K,hh,ww=p.shape
    m=(v>0.5)&(gt>0)
    pl=np.concatenate([np.full((1,hh,ww),-1),p[:-1]]); pr=np.concatenate([p[1:],np.full((1,hh,ww),-1)])
    score=np.where((p>=pl)&(p>pr),p,-1)
    top=np.argmax(score,axis=0)
    m1=rep(np.take_along_axis(h,top[None],0)[0],4); m1mass=rep(np.take_along_axis(p,top[None],0)[0],4)
    co4=rep(co,4); ha2=rep(ha,2)
    fe=np.abs(full-gt); n+=m.sum(); errall+=fe[m].sum()
    bad=m&(fe>10)
    cok=np.abs(co4-gt)<6; hok=np.abs(ha2-gt)<6; mok=np.abs(m1-gt)<6
    for name,sel in [("coarse ok, half ok, full bad",cok&hok),("coarse ok, half bad",cok&~hok),
                     ("coarse bad, half ok",~cok&hok),("coarse bad, mode1 ok, half bad",~cok&mok&~hok),
                     ("coarse bad, mode1 bad, half bad",~cok&~mok&~hok)]:
        s=bad&sel; add(name,s.sum(),fe[s].sum())
    s=bad&~cok&mok&~hok
    add("  of which mode1 mass>0.5",(s&(m1mass>0.5)).sum(),fe[s&(m1mass>0.5)].sum())
    add("  of which coarse between mode1 and full", (s&(np.abs(co4-m1)<np.abs(full-m1))).sum(),0)
    if EDGES:
        dist=edge_distance(np.where(gt>0,gt,0.0))
        s=bad&~cok&~mok&~hok
        for r in (3, 8):
            add(f"  of which within {r} px of a depth edge",(s&(dist<r)).sum(),fe[s&(dist<r)].sum())
print(d, "MAE %.3f"%(errall/n))
for k,(c,e) in C.items(): print("%-40s %.4f of pixels, %.3f MAE"%(k,c/n,e/n))
