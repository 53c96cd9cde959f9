# Stop 44: stop 43's largest miss category (../pick-7/miss_categories.py: the coarse answer, its most probable
# mode and the half stage all more than 6 index units off where the answer is more than 10 off) against the
# distance to the truth's nearest depth edge (a jump of more than 20 index units; as edge_error.py) at the
# output grid. Usage: miss_categories_edges.py DUMP_DIR A B (cascade_dump's output; omni_np.py's venv)
import json, sys
import numpy as np, scipy.ndimage as nd
d=sys.argv[1]; A,B=int(sys.argv[2]),int(sys.argv[3])
tot=0; cat=0; cat_near=0; allbad_near=0
for f in range(A,B+1):
    meta=json.load(open(f"{d}/{f:05d}.json"))
    r=lambda n: np.fromfile(f"{d}/{f:05d}_{n}.f32",dtype="<f4").reshape(meta[n])
    p=r("coarse_prob"); h=r("coarse_hyp"); gt=r("gt"); v=r("valid"); full=r("full"); co=r("coarse"); ha=r("half")
    rep=lambda a,k: np.repeat(np.repeat(a,k,axis=-2),k,axis=-1)
    K,hh,ww=p.shape
    m=(v>0.5)&(gt>0)
    pl=np.concatenate([np.full((1,hh,ww),-1),p[:-1]]); pr=np.concatenate([p[1:],np.full((1,hh,ww),-1)])
    score=np.where((p>=pl)&(p>pr),p,-1); top=np.argmax(score,axis=0)
    m1=rep(np.take_along_axis(h,top[None],0)[0],4)
    co4=rep(co,4); ha2=rep(ha,2)
    fe=np.abs(full-gt)
    bad=m&(fe>10)
    sel=bad&~(np.abs(co4-gt)<6)&~(np.abs(m1-gt)<6)&~(np.abs(ha2-gt)<6)
    g=np.where(gt>0,gt,0.0)
    dx=np.abs(g-np.roll(g,1,1))>20; dy=np.zeros_like(dx); dy[1:]=np.abs(g[1:]-g[:-1])>20
    edge=dx|np.roll(dx,-1,1)|dy|np.roll(dy,-1,0)
    dist=nd.distance_transform_edt(~edge)
    tot+=fe[m].sum(); cat+=fe[sel].sum(); cat_near+=fe[sel&(dist<3)].sum()
    allbad_near+=fe[sel&(dist<8)].sum()
print("%s %d-%d: category share of error %.3f; of it within 3 px of an edge %.3f, within 8 px %.3f"%(d,A,B,cat/tot,cat_near/cat,allbad_near/cat))
