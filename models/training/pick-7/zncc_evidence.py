# Stop 42: is the ZNCC at the coarse modes evidence enough to choose them? On the validation frames'
# pick inputs (v-SET.npz, ../pick-1/pick_inputs.py) and coarse modes (mv-SET.npz, make-data.sh):
# among the pixels the answer misses by more than 10 index units, those with a mode within 6 of the
# truth ("fixable"), and how many of them have a ZNCC at that mode above the ZNCC at the answer by
# 0.1; among the pixels the answer gets within 3, how many have a mode more than 10 away whose ZNCC
# is above the answer's by 0.1 (a switch there would break them).
# Usage: zncc_evidence.py things|house|hhouse   (the venv of ../../../../shared/tools/omni_np.py)
import sys
import numpy as np
d=np.load('/work/data2/v-%s.npz'%sys.argv[1]); m=np.load('/work/data2/mv-%s.npz'%sys.argv[1])
V=d['v']; G=d['gt']; OK=d['valid']; M=m['modes'].astype(np.float32); C=m['mode_cands']
A=dict(n=0,fix=0,fix_z=0,fix_z2=0,good=0,good_z=0)
rows=[]
for i in range(len(V)):
    v,g,ok=V[i],G[i],OK[i]; mo=M[i]; c=C[i]
    ev=np.abs(v-g); ec=np.abs(c-g[None])
    zv=mo[12]; fv=mo[13]
    zm=np.stack([mo[4*j+2] for j in range(3)]); mass=np.stack([mo[4*j+1] for j in range(3)])
    bad=ok&(ev>10)
    fixable=bad&(ec.min(0)<6)
    jbest=ec.argmin(0)
    zbest=np.take_along_axis(zm,jbest[None],0)[0]
    A['n']+=bad.sum(); A['fix']+=fixable.sum()
    A['fix_z']+=(fixable&(zbest>zv+0.1)).sum()
    good=ok&(ev<3)
    # in good pixels: any mode with |c-v|>10 and zncc > zv+0.1
    far=np.abs(c-v[None])>10
    A['good']+=good.sum(); A['good_z']+=(good&((far&(zm>zv[None]+0.1)).any(0))).sum()
print(sys.argv[1], {k:int(v) for k,v in A.items()})
print("fixable/bad %.3f; fixable with zncc(best mode) > zncc(v)+0.1: %.3f; good px with a far mode zncc > v+0.1: %.3f"%(A['fix']/A['n'],A['fix_z']/A['fix'],A['good_z']/A['good']))
