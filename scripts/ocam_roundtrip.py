#!/usr/bin/env python3
"""Independent check of how far each itbt_sample camera's inverse polynomial
strays from its forward polynomial: for angles from the optical axis, the
radius difference in pixels. Run from the repository root."""
import numpy as np, yaml
cfg=yaml.safe_load(open('../shared/data/omnimvs-samples/itbt_sample/config.yaml'))
for cam in cfg['cameras']:
    inv=np.array(cam['inv_poly'][1:]); poly=np.array(cam['poly'][1:])
    out=[]
    for a_deg in [60,80,90,95,100,105,108,110]:
        a=np.deg2rad(a_deg); theta=a-np.pi/2
        rho=np.polynomial.polynomial.polyval(theta,inv)
        z=np.polynomial.polynomial.polyval(rho,poly)
        a2=np.arctan2(rho,-z)
        # pixel error ~ drho: find rho2 s.t. angle(rho2)=a by bisection
        lo,hi=0,2000
        for _ in range(100):
            m=(lo+hi)/2
            if np.arctan2(m,-np.polynomial.polynomial.polyval(m,poly))<a: lo=m
            else: hi=m
        out.append((a_deg, round(rho-lo,3)))
    print(out)
