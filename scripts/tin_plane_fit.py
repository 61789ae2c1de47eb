#!/usr/bin/env python3
# Usage: python3 scripts/tin_plane_fit.py RUN/tin.ply ... : total-least-squares plane through all
# vertices, residuals against the per-vertex sigma (docs/EXPERIMENTS.md, fountain wall)
import struct, sys, math
def read(path):
    data = open(path,'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    header = data[:end].decode()
    props = [l.split()[2] for l in header.splitlines() if l.startswith('property') and 'list' not in l]
    props = props[:props.index('views')+1] if 'views' in props else props
    nv = int([l for l in header.splitlines() if l.startswith('element vertex')][0].split()[2])
    fmt = '<' + ''.join({'x':'d','y':'d','z':'d','nx':'f','ny':'f','nz':'f','sigma':'f','views':'i'}[p] for p in props)
    size = struct.calcsize(fmt)
    return [dict(zip(props, struct.unpack_from(fmt, data, end+i*size))) for i in range(nv)]
def smallest_eigvec(C):
    # Jacobi rotations on a symmetric 3x3
    A = [row[:] for row in C]; V = [[1.0 if i==j else 0.0 for j in range(3)] for i in range(3)]
    for _ in range(50):
        p, q = max(((i,j) for i in range(3) for j in range(i+1,3)), key=lambda t: abs(A[t[0]][t[1]]))
        if abs(A[p][q]) < 1e-18: break
        th = 0.5*math.atan2(2*A[p][q], A[q][q]-A[p][p]); c, s = math.cos(th), math.sin(th)
        for k in range(3):
            akp, akq = A[k][p], A[k][q]; A[k][p] = c*akp - s*akq; A[k][q] = s*akp + c*akq
        for k in range(3):
            apk, aqk = A[p][k], A[q][k]; A[p][k] = c*apk - s*aqk; A[q][k] = s*apk + c*aqk
        for k in range(3):
            vkp, vkq = V[k][p], V[k][q]; V[k][p] = c*vkp - s*vkq; V[k][q] = s*vkp + c*vkq
    i = min(range(3), key=lambda i: A[i][i]); return [V[k][i] for k in range(3)]
for path in sys.argv[1:]:
    vs = read(path)
    P = [(v['x'], v['y'], v['z']) for v in vs]
    n = len(P); m = [sum(p[i] for p in P)/n for i in range(3)]
    C = [[sum((p[i]-m[i])*(p[j]-m[j]) for p in P)/n for j in range(3)] for i in range(3)]
    nrm = smallest_eigvec(C)
    r = sorted(abs(sum((p[i]-m[i])*nrm[i] for i in range(3))) for p in P)
    rms = math.sqrt(sum(x*x for x in r)/n)
    sig = sorted(v['sigma'] for v in vs if 'sigma' in v)
    print(f'{path}: {n} vertices, plane residual RMS {1000*rms:.1f} mm, median {1000*r[n//2]:.1f} mm, p90 {1000*r[int(0.9*n)]:.1f} mm; vertex sigma median {1000*sig[len(sig)//2]:.2f} mm, p90 {1000*sig[int(0.9*len(sig))]:.2f} mm; share of |r| <= 3 sigma_i: ' + f"{sum(1 for v in vs if abs(sum((v['x'],v['y'],v['z'])[i]*nrm[i] for i in range(3)) - sum(m[i]*nrm[i] for i in range(3))) <= 3*v['sigma'])/n*100:.1f} %")
