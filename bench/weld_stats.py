#!/usr/bin/env python3
# Coincident vertices and sliver share (smallest angle < 10 degrees, zero-area triangles included) of a binary
# PLY that vkmesh wrote, and the same after welding the coincident positions and dropping the triangles that
# become degenerate: what sharing one vertex where two coincide would give (docs/REFINEMENT.md, "Vertices").
# Usage: /usr/bin/python3 bench/weld_stats.py MESH.ply [TOLERANCE_M]   (tolerance 0: exact float equality)
import sys, numpy as np
def read_ply(path):
    f = open(path, 'rb'); header = []
    while True:
        line = f.readline().decode().strip(); header.append(line)
        if line == 'end_header': break
    fmt = [l for l in header if l.startswith('format')][0]
    assert 'binary_little_endian' in fmt, fmt
    types = {'float': 'f4', 'uchar': 'u1', 'uint': 'u4', 'int': 'i4', 'ushort': 'u2', 'double': 'f8', 'uint8': 'u1', 'float32': 'f4', 'uint32': 'u4', 'int32': 'i4'}
    elems = []; cur = None
    for l in header:
        p = l.split()
        if p[0] == 'element': cur = [p[1], int(p[2]), []]; elems.append(cur)
        elif p[0] == 'property': cur[2].append(p[1:])
    data = {}
    for name, n, props in elems:
        if name == 'vertex':
            dt = np.dtype([(q[1], types[q[0]]) for q in props])
            data['v'] = np.frombuffer(f.read(dt.itemsize * n), dtype=dt, count=n)
        elif name == 'face':
            q = props[0]; ct, it = types[q[1]], types[q[2]]
            dt = np.dtype([('n', ct), ('i', it, 3)])
            a = np.frombuffer(f.read(dt.itemsize * n), dtype=dt, count=n)
            assert (a['n'] == 3).all(); data['f'] = a['i'].astype(np.int64)
    return data
def slivers(P, F):
    a, b, c = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    def ang(u, w):
        nu = np.linalg.norm(u, axis=1); nw = np.linalg.norm(w, axis=1)
        with np.errstate(invalid='ignore', divide='ignore'):
            cs = np.einsum('ij,ij->i', u, w) / (nu * nw)
        return np.where((nu * nw) == 0, 1.0, cs)
    cmax = np.maximum.reduce([ang(b - a, c - a), ang(a - b, c - b), ang(a - c, b - c)])
    return float((cmax > np.cos(np.radians(10))).mean())
d = read_ply(sys.argv[1]); v = d['v']
P = np.stack([v['x'], v['y'], v['z']], 1).astype(np.float64); F = d['f']
key = np.stack([v['x'], v['y'], v['z']], 1).view(np.uint32).copy()
_, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
coinc = int(len(P) - len(cnt))
# weld within tol (voxel fraction) to emulate sharing the corner's vertex
tol = float(sys.argv[2]) if len(sys.argv) > 2 else 0.0
if tol > 0:
    q = np.round(P / tol).astype(np.int64)
    _, inv2 = np.unique(q, axis=0, return_inverse=True)
else:
    inv2 = inv
F2 = inv2.reshape(-1)[F]
keep = (F2[:, 0] != F2[:, 1]) & (F2[:, 1] != F2[:, 2]) & (F2[:, 0] != F2[:, 2])
Pw = np.zeros((inv2.max() + 1, 3)); Pw[inv2.reshape(-1)] = P
print(f"vertices {len(P)} triangles {len(F)} coincident {coinc} slivers {slivers(P, F):.4f} | welded: vertices {len(Pw)} triangles {int(keep.sum())} dropped {int((~keep).sum())} slivers {slivers(Pw, F2[keep]):.4f}")
