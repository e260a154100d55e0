"""The code generator's dynamics: Eqs. 6-8 for one mechanism, on symbolic values.

``body_terms`` is dynamics.body_terms_kernel for one body and ``tree_product`` is
dynamics.tree_product for the whole tree, written out with the same sums in the same order; a
massless body (mass and inertia structurally zero) contributes nothing and is skipped, as there.
"""
from __future__ import annotations

from nsd_core.engine.codegen_kin import ModelSymbols
from nsd_core.engine.codegen_sym import Code, acc_from, add, cross, dot, mul, neg, sub


def massless(M: ModelSymbols, i: int) -> bool:
    return M.mass(i) == 0.0 and all(M.inertia(i, a, b) == 0.0 for a in range(3) for b in range(3))


def body_terms(code: Code, M: ModelSymbols, i: int, A, r, Z, Q):
    """(M_i as 6 x 6 values, Q_i) for body i; Q: the applied wrench, to which gravity and the
    velocity terms are added."""
    m = M.mass(i)
    com = [M.com(i, b) for b in range(3)]
    inertia = [[M.inertia(i, a, b) for b in range(3)] for a in range(3)]
    Ai = A[i]
    g = code.lets([acc_from(r[i][a], [(Ai[a][b], com[b]) for b in range(3)]) for a in range(3)])
    G = [code.lets([dot((Ai[a][c], inertia[c][d]) for c in range(3)) for d in range(3)]) for a in range(3)]
    JG = [code.lets([dot((G[a][d], Ai[b][d]) for d in range(3)) for b in range(3)]) for a in range(3)]
    S = [[0.0, neg(g[2]), g[1]], [g[2], 0.0, neg(g[0])], [neg(g[1]), g[0], 0.0]]
    S = [code.lets(row) for row in S]
    Mb = [[0.0] * 6 for _ in range(6)]
    for a in range(3):
        for b in range(3):
            GG = dot((S[a][c], S[c][b]) for c in range(3))
            Mb[a][b] = m if a == b else 0.0
            Mb[a][3 + b] = mul(neg(m), S[a][b])
            Mb[3 + a][b] = mul(m, S[a][b])
            Mb[3 + a][3 + b] = sub(JG[a][b], mul(m, GG))
    Mb = [code.lets(row) for row in Mb]
    t1 = code.lets([mul(m, M.gravity(a)) for a in range(3)])
    gd = cross(g, t1)
    Q = [add(Q[a], t1[a]) for a in range(3)] + [add(Q[3 + a], gd[a]) for a in range(3)]
    w = Z[i][3:]
    t1 = cross(w, g)
    gd = code.lets([add(Z[i][a], t1[a]) for a in range(3)])
    wgd = code.lets(cross(w, gd))
    Jw = code.lets([dot((JG[a][b], w[b]) for b in range(3)) for a in range(3)])
    t1 = cross(w, Jw)
    gd = cross(g, wgd)
    Q = [sub(Q[a], mul(m, wgd[a])) for a in range(3)] + [sub(Q[3 + a], add(t1[a], mul(m, gd[a]))) for a in range(3)]
    return Mb, code.lets(Q)


def tree_product(code: Code, parent, B, vp, Mb, Qb, gen, v, bias: bool):
    """out = M v - Q (bias) or M v: the accelerations root to leaves, each body's M_i a_i (- Q_i),
    subtree sums leaves to root, projections on the joints (minus the joint forces gen)."""
    n = len(parent)
    acc = [None] * n
    for i in range(n):
        p = parent[i]
        acc[i] = code.lets([add(acc[p][a] if p >= 0 else 0.0, mul(B[i][a], v[i])) for a in range(6)])
    F = [None] * n
    for i in range(n):
        Mi = Mb[i]
        light = Mi is None or all(Mi[a][a] == 0.0 for a in (0, 3, 4, 5))
        row = []
        for a in range(6):
            f = neg(Qb[i][a]) if bias else 0.0
            if not light:
                for b in range(6):
                    f = add(f, mul(Mi[a][b], add(acc[i][b], vp[i][b]) if bias else acc[i][b]))
            row.append(f)
        F[i] = code.lets(row)
    for i in range(n - 1, -1, -1):
        p = parent[i]
        if p >= 0:
            F[p] = code.lets([add(F[p][a], F[i][a]) for a in range(6)])
    out = []
    for k in range(n):
        s = dot((B[k][a], F[k][a]) for a in range(6))
        out.append(code.let(sub(s, gen[k]) if bias else s))
    return out
