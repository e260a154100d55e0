"""Random closed loops for the campaign (comparisons.campaign.generate): four-bars, slider-cranks, a
spatial RSSR, each screened in closed form away from singular positions."""
from __future__ import annotations

import math

import numpy as np

from comparisons.campaign.parts import (GRASHOF, MARGIN, _rz, body, case, gravity, inertia, outputs_for, rotation,
                                        spring, turn, unit, vec)


def fourbar_closure(a, b, c, g, theta, branch):
    """(coupler angle, rocker angle, sin of the transmission angle) of a four-bar with ground pivots
    (0, 0) and (g, 0), crank a at theta, coupler b, rocker c, on ``branch`` (+1/-1); None if it cannot close."""
    bx, by = a * math.cos(theta), a * math.sin(theta)
    dx, dy = g - bx, -by
    dist = math.hypot(dx, dy)
    if not abs(b - c) < dist < b + c:
        return None
    along = (b * b - c * c + dist * dist) / (2.0 * dist)
    h = math.sqrt(max(b * b - along * along, 0.0))
    cx = bx + (along * dx - branch * h * dy) / dist
    cy = by + (along * dy + branch * h * dx) / dist
    cos_mu = (b * b + c * c - dist * dist) / (2.0 * b * c)
    return math.atan2(cy - by, cx - bx), math.atan2(cy, cx - g), math.sqrt(max(0.0, 1.0 - cos_mu * cos_mu))


def _fourbar_lengths(d, kind: str):
    """(crank a, coupler b, rocker c, ground g) of Grashof class ``kind``."""
    s, p, q, l = sorted(d.uniform(0.04, 0.4) for _ in range(4))   # shortest, the middle two, longest
    grashof = s + l <= p + q
    if (kind == "non_grashof") == grashof:
        return None
    others = [l, p, q]
    order = [others.pop(d.integer(0, len(others) - 1)) for _ in range(2)] + others
    if kind == "crank_rocker":
        return s, order[0], order[1], order[2]
    if kind == "double_crank":
        return order[0], order[1], order[2], s
    if kind == "double_rocker":
        return order[0], s, order[1], order[2]
    links = [s, l, p, q]
    return tuple(links.pop(d.integer(0, len(links) - 1)) for _ in range(4))


def _arc(ok: np.ndarray, grid: np.ndarray):
    """The longest run of True in a circular grid: (centre, half width) in rad, or None."""
    n, best, start = len(ok), (0, 0), None
    if ok.all():
        return 0.0, math.pi
    k0 = int(np.argmin(ok))   # start scanning just after a False: runs do not wrap
    for i in range(1, n + 1):
        j = (k0 + i) % n
        if ok[j] and start is None:
            start = i
        if (not ok[j] or i == n) and start is not None:
            end = i if not ok[j] else i + 1
            if end - start > best[1] - best[0]:
                best = (start, end)
            start = None
    if best[1] - best[0] < 2:
        return None
    step = grid[1] - grid[0]
    first = grid[(k0 + best[0]) % n]
    width = (best[1] - best[0] - 1) * step
    return first + width / 2.0, width / 2.0


def four_bar(d) -> dict:
    kind = d.choice(GRASHOF)
    grid = np.linspace(0.0, 2 * math.pi, 361)[:-1]
    for _ in range(200):
        lengths = _fourbar_lengths(d, kind)
        if lengths is None:
            continue
        a, b, c, g = lengths
        branch = d.choice([1, -1])
        sol = [fourbar_closure(a, b, c, g, t, branch) for t in grid]
        ok = np.array([s is not None and s[2] >= MARGIN for s in sol])
        if kind in ("crank_rocker", "double_crank"):
            if ok.all():
                break
        else:
            arc = _arc(ok, grid)
            if arc is not None and arc[1] > math.radians(12):
                break
    else:
        raise RuntimeError(f"four_bar: no {kind} drawn in 200 tries")
    P, origin = rotation(d) if d.integer(0, 1) else np.eye(3), np.array([d.uniform(-0.1, 0.1) for _ in range(3)])
    n = P[:, 2]
    masses = [d.uniform(0.1, 1.5) for _ in range(3)]
    if kind in ("crank_rocker", "double_crank"):
        mode = d.choice(["speed", "free"])
        theta = d.uniform(-math.pi, math.pi)
        motion = {"motion": "constant_speed", "start": theta, "speed": d.choice([1, -1]) * d.uniform(2.0, 10.0)}
    else:
        mode = "harmonic"
        centre, half = arc
        amp = half * d.uniform(0.3, 0.8)
        phase = d.uniform(-math.pi, math.pi)
        motion = {"motion": "harmonic", "centre": centre, "amplitude": amp, "frequency": d.uniform(0.5, 3.0),
                  "phase": phase}
        theta = centre + amp * math.sin(phase)
    th3, th4, _ = fourbar_closure(a, b, c, g, theta, branch)
    bodies = [body("crank", "ground", {"type": "revolute", "position": vec(origin), "axis": vec(n)}, masses[0],
                   P @ [a / 2, d.uniform(-0.02, 0.02), 0.0], inertia(d, masses[0], a)),
              body("coupler", "crank", {"type": "revolute", "position": vec(P @ [a, 0, 0]), "axis": vec(n)}, masses[1],
                   P @ [b / 2, d.uniform(-0.03, 0.03), d.uniform(-0.02, 0.02)], inertia(d, masses[1], b)),
              body("rocker", "ground", {"type": "revolute", "position": vec(origin + P @ [g, 0, 0]), "axis": vec(n)},
                   masses[2], P @ [c / 2, 0.0, 0.0], inertia(d, masses[2], c))]
    loop = {"name": "C", "type": "point", "body_a": "coupler", "point_a": vec(P @ [b, 0, 0]), "body_b": "rocker",
            "point_b": vec(P @ [c, 0, 0])}
    # a spring from a coupler point to a ground point
    local = np.array([b * d.uniform(0.2, 0.8), d.uniform(-0.05, 0.05), d.uniform(-0.02, 0.02)])
    bx = np.array([a * math.cos(theta), a * math.sin(theta), 0.0])
    world = origin + P @ (bx + _rz(th3) @ local)
    anchor = origin + P @ [d.uniform(-0.1, g + 0.1), d.uniform(0.1, 0.4) * d.choice([1, -1]), d.uniform(-0.05, 0.05)]
    forces = [spring("spring", "coupler", P @ local, "ground", anchor, float(np.linalg.norm(world - anchor)), d,
                     sum(masses))]
    if d.integer(0, 2) == 0:
        forces.append({"name": "rocker_torsion", "law": "joint_spring_damper", "joint": "rocker",
                       "parameters": {"stiffness": d.uniform(0.1, 5.0), "damping": d.uniform(0.0, 0.05),
                                      "neutral": th4}})
    description = {"model": {"name": f"four_bar_{kind}", "source": f"generated: four-bar, {kind}, branch {branch}, "
                             f"a={a:.4g} b={b:.4g} c={c:.4g} g={g:.4g} m, {mode}", "gravity": gravity(d)},
                   "bodies": bodies, "loops": [loop], "forces": forces}
    guess = {"coupler": th3 - theta + d.uniform(-0.02, 0.02), "rocker": th4 + d.uniform(-0.02, 0.02)}
    out = [("rocker_angle", "coordinate", {"joint": "rocker"}),
           ("coupler_point", "point", {"body": "coupler", "point": vec(P @ local), "component": d.choice("xyz")}),
           ("coupler_point_v", "point_velocity", {"body": "coupler", "point": vec(P @ local),
                                                  "component": d.choice("xyz")}),
           ("spring_force", "force", {"element": "spring"})]
    if mode == "free":
        description["initial"] = {"coordinates": {"crank": theta, **guess},
                                  "velocities": {"crank": d.uniform(-8.0, 8.0)}, "free": ["crank"]}
        out.append(("kinetic", "energy", {"term": "kinetic"}))
    else:
        description["prescribed"] = [{"name": "motor", "joint": "crank", **motion}]
        description["initial"] = {"coordinates": guess}
        out.append(("drive_torque", "drive_force", {"element": "motor"}))
    description["outputs"] = outputs_for(out)
    description["case"] = [case(d)]
    return description


def slider_crank(d) -> dict:
    """A crank r on the ground, a rod l on its pin, a slider along the plane's x at offset e."""
    r = d.uniform(0.03, 0.12)
    for _ in range(200):
        l, e = r * d.uniform(2.0, 5.0), d.uniform(-0.6, 0.6) * r
        if (r + abs(e)) / l <= math.cos(math.asin(MARGIN)) * 0.95:
            break
    P = rotation(d) if d.integer(0, 1) else np.eye(3)
    origin = np.array([d.uniform(-0.1, 0.1) for _ in range(3)])
    n, mode = P[:, 2], d.choice(["speed", "free"])
    theta = d.uniform(-math.pi, math.pi)
    s = math.sqrt(l * l - (r * math.sin(theta) - e) ** 2)
    x = r * math.cos(theta) + s
    phi = math.atan2(e - r * math.sin(theta), x - r * math.cos(theta))
    m = [d.uniform(0.1, 1.5) for _ in range(3)]
    bodies = [body("crank", "ground", {"type": "revolute", "position": vec(origin), "axis": vec(n)}, m[0],
                   P @ [r / 2, 0.0, 0.0], inertia(d, m[0], r)),
              body("rod", "crank", {"type": "revolute", "position": vec(P @ [r, 0, 0]), "axis": vec(n)}, m[1],
                   P @ [l * d.uniform(0.3, 0.6), 0.0, 0.0], inertia(d, m[1], l)),
              body("slider", "ground", {"type": "prismatic", "position": vec(origin + P @ [0, e, 0]), "axis": vec(P[:, 0])},
                   m[2], [0.0, 0.0, 0.0], inertia(d, m[2], 0.05))]
    forces = [{"name": "slider_spring", "law": "joint_spring_damper", "joint": "slider",
               "parameters": {"stiffness": sum(m) * d.uniform(10.0, 400.0), "damping": d.uniform(0.0, 2.0),
                              "neutral": r * d.uniform(-1.0, 1.0) + math.sqrt(l * l - e * e)}}]
    description = {"model": {"name": "slider_crank", "source": f"generated: slider-crank r={r:.4g} l={l:.4g} e={e:.4g} m, "
                             f"{mode}", "gravity": gravity(d)},
                   "bodies": bodies, "forces": forces,
                   "loops": [{"name": "pin", "body_a": "rod", "point_a": vec(P @ [l, 0, 0]), "body_b": "slider"}]}
    guess = {"rod": phi - theta + d.uniform(-0.02, 0.02), "slider": x + d.uniform(-0.002, 0.002)}
    out = [("slider_x", "coordinate", {"joint": "slider"}), ("rod_angle", "coordinate", {"joint": "rod"}),
           ("slider_v", "point_velocity", {"body": "slider", "component": d.choice("xyz")}),
           ("spring_force", "force", {"element": "slider_spring"})]
    if mode == "free":
        description["initial"] = {"coordinates": {"crank": theta, **guess},
                                  "velocities": {"crank": d.uniform(-10.0, 10.0)}, "free": ["crank"]}
        out.append(("kinetic", "energy", {"term": "kinetic"}))
    else:
        description["prescribed"] = [{"name": "motor", "joint": "crank", "motion": "constant_speed", "start": theta,
                                      "speed": d.choice([1, -1]) * d.uniform(2.0, 12.0)}]
        description["initial"] = {"coordinates": guess}
        out.append(("drive_torque", "drive_force", {"element": "motor"}))
    description["outputs"] = outputs_for(out)
    description["case"] = [case(d)]
    return description


def rssr_rocker(B, D, u, c_vec, b, phi0: float) -> tuple[float, float] | None:
    """The rocker angle near phi0 closing an RSSR (|D + turn(u, phi) c_vec - B| = b) and the closure's
    sensitivity |d|C - B|/dphi| / c (0 at a singular position); None if Newton fails."""
    phi, c = phi0, float(np.linalg.norm(c_vec))
    for _ in range(40):
        C = D + turn(u, phi) @ c_vec
        dC = np.cross(u, C - D)
        f = float((C - B) @ (C - B)) - b * b
        df = 2.0 * float((C - B) @ dC)
        if abs(df) < 1e-12:
            return None
        phi -= f / df
        if abs(f) < 1e-15:
            break
    C = D + turn(u, phi) @ c_vec
    return (phi, abs(float((C - B) @ np.cross(u, C - D))) / (b * c)) if abs(float((C - B) @ (C - B)) - b * b) < 1e-12 else None


def spatial_rssr(d) -> dict:
    """A crank turning about n1 on the ground, a coupler on a spherical joint at its tip, a rocker turning
    about u at D, the coupler's far end pinned to the rocker's (a point closure: the second spherical)."""
    for _ in range(200):
        n1 = unit(d)
        a_vec = np.cross(n1, unit(d))
        if np.linalg.norm(a_vec) < 0.3:
            continue
        a_vec *= d.uniform(0.04, 0.12) / np.linalg.norm(a_vec)
        D = np.array([d.uniform(-0.3, 0.3) for _ in range(3)])
        u = unit(d)
        c_vec = np.cross(u, unit(d))
        if np.linalg.norm(c_vec) < 0.3 or not 0.1 < np.linalg.norm(D) < 0.4:
            continue
        c_vec *= d.uniform(0.1, 0.3) / np.linalg.norm(c_vec)
        B, C = a_vec, D + c_vec
        b = float(np.linalg.norm(C - B))
        if not 0.1 < b < 0.6:
            continue
        amp = d.uniform(0.2, 0.6)
        phi, ok = 0.0, True
        for t in np.linspace(0.0, amp, 40):   # continuation over the drive's arc, both ways from 0
            r = rssr_rocker(turn(n1, t) @ a_vec, D, u, c_vec, b, phi)
            ok = ok and r is not None and r[1] >= MARGIN
            phi = r[0] if r else phi
        phi = 0.0
        for t in np.linspace(0.0, -amp, 40):
            r = rssr_rocker(turn(n1, t) @ a_vec, D, u, c_vec, b, phi)
            ok = ok and r is not None and r[1] >= MARGIN
            phi = r[0] if r else phi
        if ok:
            break
    else:
        raise RuntimeError("spatial_rssr: no mechanism drawn in 200 tries")
    m = [d.uniform(0.1, 1.0) for _ in range(3)]
    bodies = [body("crank", "ground", {"type": "revolute", "position": [0.0, 0.0, 0.0], "axis": vec(n1)}, m[0],
                   a_vec / 2, inertia(d, m[0], float(np.linalg.norm(a_vec)))),
              body("coupler", "crank", {"type": "spherical", "position": vec(a_vec)}, m[1], (C - B) / 2,
                   inertia(d, m[1], b)),
              body("rocker", "ground", {"type": "revolute", "position": vec(D), "axis": vec(u)}, m[2], c_vec / 2,
                   inertia(d, m[2], float(np.linalg.norm(c_vec))))]
    description = {"model": {"name": "spatial_rssr", "source": f"generated: RSSR, coupler {b:.4g} m, drive +-{amp:.3g} rad",
                             "gravity": gravity(d)},
                   "bodies": bodies,
                   "loops": [{"name": "S2", "body_a": "coupler", "point_a": vec(C - B), "body_b": "rocker",
                              "point_b": vec(c_vec)}],
                   "forces": [spring("spring", "rocker", c_vec, "ground", D + c_vec + 0.1 * unit(d), 0.1, d, sum(m))],
                   "prescribed": [{"name": "motor", "joint": "crank", "motion": "harmonic", "amplitude": amp,
                                   "frequency": d.uniform(0.5, 2.0)}],
                   "initial": {"coordinates": {"coupler": [0.0, 0.0, 0.0], "rocker": 0.0}}}
    description["outputs"] = outputs_for([
        ("rocker_angle", "coordinate", {"joint": "rocker"}),
        ("coupler_mid", "point", {"body": "coupler", "point": vec((C - B) / 2), "component": d.choice("xyz")}),
        ("spring_force", "force", {"element": "spring"}),
        ("drive_torque", "drive_force", {"element": "motor"})])
    description["case"] = [case(d)]
    return description
