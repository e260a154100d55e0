"""The code generator's kinematics: Eqs. 2-5, 13-14 and the two-point elements, one body at a time.

Each function is the generic kernel of the same name (nsd_core.engine.kinematics, closure,
elements, dynamics.linear_momentum_kernel) written out for one body, cut or element on symbolic
values (nsd_core.engine.codegen_sym): the same sums in the same order, the structural zeros left
out. ``ModelSymbols`` reads the model's numbers at run time: a value that is exactly 0 (or, for a
joint axis, exactly 1) in the model is structure and becomes a constant; every other number is a
local loaded from the model array when the generated function starts.
"""
from __future__ import annotations

from nsd_core.engine.codegen_sym import Code, add, cross, div, dot, mul, sub

IDENTITY = [[1.0 if a == b else 0.0 for b in range(3)] for a in range(3)]


class ModelSymbols:
    """Symbolic view of a SystemModel's numbers; ``loads`` are the prologue's lines."""

    def __init__(self, model):
        self.model = model
        self.loads: dict[str, str] = {}

    def _get(self, field: str, index: tuple, ones: bool = False):
        v = float(getattr(self.model, field)[index])
        if v == 0.0 or (ones and v == 1.0):
            return v
        name = f"{field}_" + "_".join(str(i) for i in index)
        self.loads[name] = f"m.{field}[{', '.join(str(i) for i in index)}]"
        return name

    def axis(self, i, b):
        return self._get("axis", (i, b), ones=True)

    def offset(self, i, b):
        return self._get("offset", (i, b))

    def mass(self, i):
        return self._get("mass", (i,))

    def com(self, i, b):
        return self._get("com", (i, b))

    def inertia(self, i, a, b):
        return self._get("inertia", (i, a, b))

    def gravity(self, a):
        return self._get("gravity", (a,))

    def vec(self, field, k, a):
        return self._get(field, (k, a))

    def prologue(self) -> list[str]:
        return [f"{k} = {v}" for k, v in self.loads.items()]


def rodrigues(x, y, z, c, s):
    """kinematics._rodrigues on symbols (c, s: cos and sin of the angle)."""
    C = sub(1.0, c)
    return [[add(c, mul(mul(x, x), C)), sub(mul(mul(x, y), C), mul(z, s)), add(mul(mul(x, z), C), mul(y, s))],
            [add(mul(mul(y, x), C), mul(z, s)), add(c, mul(mul(y, y), C)), sub(mul(mul(y, z), C), mul(x, s))],
            [sub(mul(mul(z, x), C), mul(y, s)), add(mul(mul(z, y), C), mul(x, s)), add(c, mul(mul(z, z), C))]]


def body_position(code: Code, M: ModelSymbols, i: int, jtype: int, zi, Ap, rp):
    """positions_kernel for body i: (A_i, r_i, b_i) from the parent's (A_p, r_p) (None: the ground)."""
    Ap = IDENTITY if Ap is None else Ap
    axis = [M.axis(i, b) for b in range(3)]
    off = [M.offset(i, b) for b in range(3)]
    u = code.lets([dot((Ap[a][b], axis[b]) for b in range(3)) for a in range(3)])
    d = code.lets([add(dot((Ap[a][b], off[b]) for b in range(3)), 0.0 if rp is None else rp[a])
                   for a in range(3)])
    if jtype == 1:
        c, s = code.let(f"math.cos({zi})"), code.let(f"math.sin({zi})")
        R = [code.lets(row) for row in rodrigues(*axis, c, s)]
        A = [code.lets([dot((Ap[a][cc], R[cc][b]) for cc in range(3)) for b in range(3)]) for a in range(3)]
        r = list(d)
        B = code.lets(cross(d, u)) + list(u)
    else:
        A = [list(row) for row in Ap]
        r = code.lets([add(d[a], mul(zi, u[a])) for a in range(3)])
        B = list(u) + [0.0, 0.0, 0.0]
    return A, r, B


def global_point(body, local, A, r, is_point):
    """closure._global / elements._point_state's position: r + A local (the ground: local)."""
    if body < 0:
        return list(local)
    out = []
    for a in range(3):
        acc = r[body][a] if is_point else 0.0
        for b in range(3):
            acc = add(acc, mul(A[body][a][b], local[b]))
        out.append(acc)
    return out


def cut_positions(code: Code, M: ModelSymbols, model, A, r, B, parent, cols):
    """closure_kernel's Phi and the Phi_z columns ``cols`` (with_positions), rows in the model's order.
    Returns (Phi list, J dict (row, col) -> value), structural zeros as constants."""
    Phi, J = [], {}
    for k, kind in enumerate(model.cut_kind):
        ca, cb = int(model.cut_a[k]), int(model.cut_b[k])
        va = [M.vec("cut_va", k, a) for a in range(3)]
        vb = [M.vec("cut_vb", k, a) for a in range(3)]
        row = len(Phi)
        if kind == 0:
            phi = [0.0, 0.0, 0.0]
            for side, (body, v) in enumerate(((ca, va), (cb, vb))):
                sign = 1.0 if side == 0 else -1.0
                p = code.lets(global_point(body, v, A, r, True))
                for a in range(3):
                    phi[a] = add(phi[a], mul(sign, p[a]))
                j = body
                while j >= 0:
                    t1 = cross(B[j][3:], p)
                    for a in range(3):
                        if j in cols:
                            J[row + a, j] = add(J.get((row + a, j), 0.0), mul(sign, add(B[j][a], t1[a])))
                    j = parent[j]
            Phi += phi
        else:
            av = code.lets(global_point(ca, va, A, r, False))
            bv = code.lets(global_point(cb, vb, A, r, False))
            axb = code.lets(cross(av, bv))
            Phi.append(dot((av[a], bv[a]) for a in range(3)))
            for side, j in enumerate((ca, cb)):
                sign = 1.0 if side == 0 else -1.0
                while j >= 0:
                    if j in cols:
                        J[row, j] = add(J.get((row, j), 0.0),
                                        mul(sign, dot((B[j][3 + a], axb[a]) for a in range(3))))
                    j = parent[j]
    return Phi, J


def cut_rates(code: Code, M: ModelSymbols, model, A, r, Z, vp):
    """closure_kernel's c (with_rates): the velocity-product term of Phi_z z'' + c = 0."""
    c = []
    for k, kind in enumerate(model.cut_kind):
        ca, cb = int(model.cut_a[k]), int(model.cut_b[k])
        va = [M.vec("cut_va", k, a) for a in range(3)]
        vb = [M.vec("cut_vb", k, a) for a in range(3)]
        if kind == 0:
            acc = [0.0, 0.0, 0.0]
            for side, (body, v) in enumerate(((ca, va), (cb, vb))):
                if body < 0:
                    continue
                sign = 1.0 if side == 0 else -1.0
                p = code.lets(global_point(body, v, A, r, True))
                t1 = cross(Z[body][3:], p)
                vel = code.lets([add(Z[body][a], t1[a]) for a in range(3)])
                t1 = code.lets(cross(vp[body][3:], p))
                t2 = code.lets(cross(Z[body][3:], vel))
                for a in range(3):
                    acc[a] = add(acc[a], mul(sign, add(add(vp[body][a], t1[a]), t2[a])))
            c += acc
        else:
            av = code.lets(global_point(ca, va, A, r, False))
            bv = code.lets(global_point(cb, vb, A, r, False))
            axb = code.lets(cross(av, bv))
            wa, wb, al = [0.0] * 3, [0.0] * 3, [0.0] * 3
            if ca >= 0:
                wa = list(Z[ca][3:])
                al = [add(al[a], vp[ca][3 + a]) for a in range(3)]
            if cb >= 0:
                wb = list(Z[cb][3:])
                al = [sub(al[a], vp[cb][3 + a]) for a in range(3)]
            t2 = code.lets(cross(code.lets(cross(wa, av)), bv))
            vel = code.lets(cross(av, code.lets(cross(wb, bv))))
            acc = 0.0
            for a in range(3):
                acc = add(acc, add(mul(add(t2[a], vel[a]), sub(wa[a], wb[a])), mul(axb[a], al[a])))
            c.append(acc)
    return [code.let(v) for v in c]


def body_velocity(code: Code, i: int, parent: int, jtype: int, B, r, zd, Z, vp):
    """velocities_kernel for body i: (Z_i, vp_i) (Eqs. 4-5)."""
    if parent < 0:
        return code.lets([mul(B[i][a], zd) for a in range(6)]), [0.0] * 6
    w = Z[parent][3:]
    if jtype == 1:
        u = B[i][3:]
        udot = code.lets(cross(w, u))
        t1 = cross(w, r[i])
        ddot = code.lets([add(Z[parent][a], t1[a]) for a in range(3)])
        t1 = code.lets(cross(ddot, u))
        t2 = code.lets(cross(r[i], udot))
        v = [add(vp[parent][a], mul(add(t1[a], t2[a]), zd)) for a in range(3)]
        v += [add(vp[parent][3 + a], mul(udot[a], zd)) for a in range(3)]
    else:
        udot = code.lets(cross(w, B[i][:3]))
        v = [add(vp[parent][a], mul(udot[a], zd)) for a in range(3)] + list(vp[parent][3:])
    Zi = [add(Z[parent][a], mul(B[i][a], zd)) for a in range(6)]
    return code.lets(Zi), code.lets(v)


def point_state(code: Code, body, local, A, r, Z):
    """elements._point_state: position and velocity of a body point."""
    p = code.lets(global_point(body, local, A, r, True))
    if body < 0:
        return p, [0.0, 0.0, 0.0]
    w0, w1, w2 = Z[body][3:]
    v = [sub(add(Z[body][0], mul(w1, p[2])), mul(w2, p[1])), sub(add(Z[body][1], mul(w2, p[0])), mul(w0, p[2])),
         sub(add(Z[body][2], mul(w0, p[1])), mul(w1, p[0]))]
    return p, code.lets(v)


def element(code: Code, M: ModelSymbols, e: int, up: int, lo: int, A, r, Z):
    """element_kinematics for element e: (P_up, P_lo, N, L, L')."""
    pu, vu = point_state(code, up, [M.vec("elem_pu", e, a) for a in range(3)], A, r, Z)
    pl, vl = point_state(code, lo, [M.vec("elem_pl", e, a) for a in range(3)], A, r, Z)
    d = code.lets([sub(pu[a], pl[a]) for a in range(3)])
    length = code.let(f"math.sqrt({add(add(mul(d[0], d[0]), mul(d[1], d[1])), mul(d[2], d[2]))})")
    N = code.lets([div(d[a], length) for a in range(3)])
    Ld = code.let(add(add(mul(N[0], sub(vu[0], vl[0])), mul(N[1], sub(vu[1], vl[1]))), mul(N[2], sub(vu[2], vl[2]))))
    return pu, pl, N, length, Ld


def momentum(code: Code, M: ModelSymbols, n: int, A, r, Z):
    """linear_momentum_kernel: sum m_i (s'_i + w_i x g_i)."""
    out = [0.0, 0.0, 0.0]
    for i in range(n):
        m = M.mass(i)
        if m == 0.0:
            continue
        com = [M.com(i, b) for b in range(3)]
        g = code.lets([add(add(add(r[i][a], mul(A[i][a][0], com[0])), mul(A[i][a][1], com[1])),
                           mul(A[i][a][2], com[2])) for a in range(3)])
        w0, w1, w2 = Z[i][3:]
        out[0] = add(out[0], mul(m, sub(add(Z[i][0], mul(w1, g[2])), mul(w2, g[1]))))
        out[1] = add(out[1], mul(m, sub(add(Z[i][1], mul(w2, g[0])), mul(w0, g[2]))))
        out[2] = add(out[2], mul(m, sub(add(Z[i][2], mul(w0, g[1])), mul(w1, g[0]))))
        out = code.lets(out)
    return out

