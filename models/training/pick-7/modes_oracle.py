# Stop 42: would the coarse stage's modes pay as candidates? On cascade_dump output (../coarse-sgm/README.md:
# `cascade_dump WEIGHTS DATASET 481 490 DIR`, the bundled cascade, no pick), over non-sky valid pixels of
# the training ground truth: the MAE (index units of N = 192), the share of pixels off by more than
# 10 and of the error they carry, how often the truth lies within 6 of the 1st / 2nd / 3rd most probable
# mode (local maxima of the coarse distribution ranked by probability, their sphere's index; each
# coarse pixel repeated over its 4 x 4 output pixels) where the answer is off by more than 10, and
# the MAE an oracle choosing among the answer and the two or three modes would remove.
# Usage: modes_oracle.py DUMP_DIR A B   (the venv of ../../../../shared/tools/omni_np.py)
import json, sys
import numpy as np
d=sys.argv[1]; A,B=int(sys.argv[2]),int(sys.argv[3])
S=dict(n=0,bad=0,errall=0.,errbad=0.,m1=0,m2=0,m3=0,gain2=0.,gain3=0.)
for f in range(A,B+1):
    meta=json.load(open(f"{d}/{f:05d}.json"))
    r=lambda n: np.fromfile(f"{d}/{f:05d}_{n}.f32",dtype="<f4").reshape(meta[n])
    p=r("coarse_prob"); h=r("coarse_hyp"); gt=r("gt"); v=r("valid"); full=r("full")
    K,hh,ww=p.shape
    rep=lambda a: np.repeat(np.repeat(a,4,axis=-2),4,axis=-1)
    m=(v>0.5)&(gt>0)
    pl=np.concatenate([np.full((1,hh,ww),-1),p[:-1]]); pr=np.concatenate([p[1:],np.full((1,hh,ww),-1)])
    score=np.where((p>=pl)&(p>pr),p,-1)
    order=np.argsort(-score,axis=0)[:3]
    M=rep(np.take_along_axis(h,order,axis=0)); VM=rep(np.take_along_axis(score,order,axis=0)>0)
    fe=np.abs(full-gt)
    bad=m&(fe>10)
    dd=[np.where(VM[i],np.abs(M[i]-gt),1e9) for i in range(3)]
    S['n']+=m.sum(); S['bad']+=bad.sum(); S['errall']+=fe[m].sum(); S['errbad']+=fe[bad].sum()
    S['m1']+=(bad&(dd[0]<6)).sum(); S['m2']+=(bad&(dd[0]>=6)&(dd[1]<6)).sum(); S['m3']+=(bad&(dd[0]>=6)&(dd[1]>=6)&(dd[2]<6)).sum()
    # oracle: replace by best of modes when within 6 -> error approx residual
    best2=np.minimum(dd[0],dd[1]); best3=np.minimum(best2,dd[2])
    S['gain2']+=np.where(bad&(best2<6),fe-best2,0).sum(); S['gain3']+=np.where(bad&(best3<6),fe-best3,0).sum()
n=S['n']
print(d,"MAE(units) %.2f bad>10 frac %.3f carry %.2f of err; bad w/ truth near mode1 %.3f mode2 %.3f mode3 %.3f; oracle MAE gain top2 %.2f top3 %.2f"%(S['errall']/n,S['bad']/n,S['errbad']/S['errall'],S['m1']/S['bad'],S['m2']/S['bad'],S['m3']/S['bad'],S['gain2']/n,S['gain3']/n))
