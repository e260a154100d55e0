"""Read a model description (TOML) into nsd_core.model.description's dataclasses, one clear error per
mistake: ``ModelError`` names the element, the field, the value and what is allowed (exit code 2).

The file format is documented, with a worked example, in docs/models.md; the device's own models and
the benchmark mechanisms are files under models/.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from nsd_core.model.description import (COMPONENTS, GROUND, JOINT_DOFS, MOTION_KINDS, MOTION_PARSERS, OUTPUT_KINDS,
                                        WORK_SOURCES,
                                        Body, ForceElement, Joint, Loop, Model, Output, Prescribed)
from nsd_core.model.bounds import check_sizes
from nsd_core.model.errors import ModelError
from nsd_core.model.excitation import parse_excitation
from nsd_core.model.laws import JOINT, PLANE, POINTS, get_law
from nsd_core.model.load_fields import (_body_ref, _fields, _inertia, _is_name, _isnumber, _list, _name, _unique, _vec,
                                        _where, number, read_toml)
from nsd_core.model.load_plane import plane_component, plane_dofs

POINT_UNITS = {"point": "m", "point_velocity": "m/s", "point_acceleration": "m/s^2"}
# the direction keys each joint type uses (docs/models.md's joint table); any other is refused
JOINT_KEYS = {"revolute": ("axis",), "prismatic": ("axis",), "universal": ("axis", "axis2"), "spherical": (),
              "planar": ("normal",), "planar_translation": ("normal",), "translational": ()}
MAX_COORDINATE = 1e6   # m or rad: an initial coordinate beyond has a resolution coarser than 1e-10 (a step is lost)
TURN = 2.0 * math.pi   # an angle beyond this in magnitude looks like degrees (angles_in_degrees)
TOP = {"model", "bodies", "loops", "forces", "prescribed", "outputs", "initial", "case", "excitation"}


def load_model(path) -> Model:
    """The description in file ``path`` (ModelError for a missing file, bad TOML or any mistake)."""
    return parse_model(read_toml(path, "--model"), str(Path(path)))


def parse_model(raw: dict, path: str = "") -> Model:
    _fields("model file", raw, TOP, ("bodies",))
    check_sizes(raw)   # the work's bounds, before any table is parsed
    head = _fields("[model]", raw.get("model", {}), {"name", "source", "gravity", "description"})
    bodies = _bodies(raw["bodies"])
    names = {b.name for b in bodies}
    loops = tuple(_loop(i, t, names) for i, t in enumerate(_list("loops", raw.get("loops", []))))
    forces = tuple(_force(i, t, bodies) for i, t in enumerate(_list("forces", raw.get("forces", []))))
    prescribed = tuple(_prescribed(i, t, bodies) for i, t in enumerate(_list("prescribed", raw.get("prescribed", []))))
    taken = {}
    for p in prescribed:
        if (p.joint, p.dof) in taken:
            raise ModelError(f"prescribed.{p.name}: coordinate {p.joint}[{p.dof}] is already prescribed")
        taken[(p.joint, p.dof)] = p.name
    model = Model(name=str(head.get("name", Path(path).stem or "model")), source=str(head.get("source", "")),
                  gravity=_vec("[model].gravity", head.get("gravity", [0.0, 0.0, 0.0])), bodies=bodies,
                  loops=loops, forces=forces, prescribed=prescribed, outputs=(), path=path,
                  excitation=parse_excitation(raw.get("excitation")))
    outputs = tuple(_output(i, t, model) for i, t in enumerate(_list("outputs", raw.get("outputs", []))))
    if not outputs:
        raise ModelError("[[outputs]]: missing; name at least one quantity to compare")
    _unique("forces", forces)
    _unique("prescribed", prescribed)
    _unique("outputs", outputs)
    _unique("loops", loops)
    init = _initial(raw.get("initial", {}), bodies, {(p.joint, p.dof): p for p in prescribed})
    return Model(**{**model.__dict__, "outputs": outputs, **init})


def _bodies(items) -> tuple[Body, ...]:
    items = _list("bodies", items)
    if not items:
        raise ModelError("[[bodies]]: at least one body is needed")
    out, names = [], {}
    for i, t in enumerate(items):
        # a body is named by its name wherever it is known (its index only when the name is missing or bad)
        given = t.get("name") if isinstance(t, dict) else None
        where = f"bodies.{given}" if _is_name(given) and given not in names else f"bodies[{i}]"
        _fields(where, t, {"name", "parent", "joint", "mass", "com", "inertia", "source"}, ("name", "joint", "mass"))
        name = _name(f"{where}.name", t["name"])
        where = f"bodies.{name}"
        if name == GROUND or name in names:
            raise ModelError(f"{where}.name = {name!r}: must be unique and not 'ground'")
        parent = t.get("parent", GROUND)
        if parent != GROUND and parent not in names:
            raise ModelError(f"{where}.parent = {parent!r}: unknown body; a parent must be 'ground' or a body "
                             "listed before it (close loops with [[loops]])")
        jt = _fields(f"{where}.joint", t["joint"], {"type", "position", "axis", "axis2", "normal"}, ("type",))
        if jt["type"] not in JOINT_DOFS:
            raise ModelError(f"{where}.joint.type = {jt['type']!r}: allowed: {', '.join(JOINT_DOFS)}")
        for k in ("axis", "axis2", "normal"):   # a direction the joint does not use would be ignored: refused
            if k in jt and k not in JOINT_KEYS[jt["type"]]:
                uses = ", ".join(JOINT_KEYS[jt["type"]]) or "no direction"
                raise ModelError(f"{where}.joint.{k}: not a key of a {jt['type']} joint (it uses {uses}); "
                                 "remove it or change the joint's type")
        axis = jt.get("normal" if jt["type"].startswith("planar") else "axis", [0.0, 0.0, 1.0])
        joint = Joint(jt["type"], _vec(f"{where}.joint.position", jt.get("position", [0.0, 0.0, 0.0])),
                      _vec(f"{where}.joint.axis", axis, nonzero=True),
                      _vec(f"{where}.joint.axis2", jt.get("axis2", [0.0, 1.0, 0.0]), nonzero=True))
        if jt["type"] == "universal" and np.linalg.norm(np.cross(joint.axis, joint.axis2)) < 1e-9 * np.linalg.norm(joint.axis) * np.linalg.norm(joint.axis2):
            raise ModelError(f"{where}.joint.axis2 = {list(joint.axis2)}: must not be parallel to axis")
        mass = number(f"{where}.mass", t["mass"], 0.0, strict_low=True) if _isnumber(t["mass"]) and t["mass"] > 0 else None
        if mass is None:
            raise ModelError(f"{where}.mass = {t['mass']!r}: must be a number > 0 [kg] (every described body moves)")
        out.append(Body(name, parent, joint, mass, _vec(f"{where}.com", t.get("com", [0.0, 0.0, 0.0])),
                        _inertia(f"{where}.inertia", t.get("inertia", [0.0, 0.0, 0.0])), str(t.get("source", ""))))
        names[name] = i
    return tuple(out)


def _loop(i: int, t: dict, names) -> Loop:
    where = _where("loops", i, t)
    _fields(where, t, {"name", "type", "body_a", "point_a", "body_b", "point_b", "axis_a", "axis_b"},
            ("body_a", "body_b"))
    name = _name(f"{where}.name", t.get("name", f"loop{i}"))
    where = f"loops.{name}"
    kind = t.get("type", "point")
    if kind not in ("point", "revolute"):
        raise ModelError(f"{where}.type = {kind!r}: allowed: point, revolute")
    a, b = _body_ref(f"{where}.body_a", t["body_a"], names), _body_ref(f"{where}.body_b", t["body_b"], names)
    if a == b:
        raise ModelError(f"{where}.body_b = {b!r}: must differ from body_a")
    axes = {}
    if kind == "revolute":
        for k in ("axis_a", "axis_b"):
            if k not in t:
                raise ModelError(f"{where}.{k}: missing (a revolute closure keeps axis_a parallel to axis_b)")
            axes[k] = _vec(f"{where}.{k}", t[k], nonzero=True)
    return Loop(name, kind, a, _vec(f"{where}.point_a", t.get("point_a", [0.0, 0.0, 0.0])), b,
                _vec(f"{where}.point_b", t.get("point_b", [0.0, 0.0, 0.0])), **axes)


def _dof(where: str, t: dict, bodies, key="joint") -> tuple[str, int]:
    names = {b.name: b for b in bodies}
    body = t.get(key)
    if body not in names:
        raise ModelError(f"{where}.{key} = {body!r}: must name a body (its joint to its parent); "
                         f"allowed: {', '.join(names)}")
    n = JOINT_DOFS[names[body].joint.type]
    dof = t.get("dof", 0)
    if isinstance(dof, bool) or not isinstance(dof, int) or not 0 <= dof < n:
        raise ModelError(f"{where}.dof = {dof!r}: must be a whole number in [0, {n - 1}] "
                         f"({body}'s {names[body].joint.type} joint has {n})")
    return body, dof


def _force(i: int, t: dict, bodies) -> ForceElement:
    where = _where("forces", i, t)
    _fields(where, t, {"name", "law", "body_a", "point_a", "body_b", "point_b", "joint", "dof", "dofs", "parameters",
                       "direction"}, ("law",))
    name = _name(f"{where}.name", t.get("name", f"force{i}"))
    where = f"forces.{name}"
    law = get_law(t["law"], where)
    params = t.get("parameters", {})
    if not isinstance(params, dict):
        raise ModelError(f"{where}.parameters = {params!r}: must be a table")
    packed = law.pack(params, f"{where}.parameters")
    names = {b.name for b in bodies}
    if law.acts_on == POINTS:
        for k in ("joint", "dof"):
            if k in t:
                raise ModelError(f"{where}.{k}: law {law.name!r} acts between two points (body_a/point_a, body_b/point_b)")
        a = _body_ref(f"{where}.body_a", t.get("body_a", GROUND), names)
        b = _body_ref(f"{where}.body_b", t.get("body_b", GROUND), names)
        if a == b:
            raise ModelError(f"{where}.body_b = {b!r}: must differ from body_a")
        direction = None
        if "direction" in t:
            e = np.asarray(_vec(f"{where}.direction", t["direction"], nonzero=True))
            direction = tuple(e / np.linalg.norm(e))
        return ForceElement(name, law, packed, dict(params), a, _vec(f"{where}.point_a", t.get("point_a", [0, 0, 0])),
                            b, _vec(f"{where}.point_b", t.get("point_b", [0, 0, 0])), direction=direction)
    what = "two slide coordinates of a joint (joint, dofs)" if law.acts_on == PLANE else "a joint coordinate (joint, dof)"
    for k in ("body_a", "point_a", "body_b", "point_b", "direction", "dofs" if law.acts_on == JOINT else "dof"):
        if k in t:
            raise ModelError(f"{where}.{k}: law {law.name!r} acts on {what}")
    if law.acts_on == PLANE:
        body, _ = _dof(where, t, bodies)   # (no "dof": refused above)
        dofs = plane_dofs(where, t.get("dofs"), next(b for b in bodies if b.name == body))
        return ForceElement(name, law, packed, dict(params), joint=body, dof=dofs[0], dofs=dofs)
    body, dof = _dof(where, t, bodies)
    return ForceElement(name, law, packed, dict(params), joint=body, dof=dof)


def _prescribed(i: int, t: dict, bodies) -> Prescribed:
    where = _where("prescribed", i, t)
    _fields(where, t, {"name", "joint", "dof", "motion"} | {k for v in MOTION_KINDS.values() for k in v},
            ("joint", "motion"))
    name = _name(f"{where}.name", t.get("name", f"drive{i}"))
    where = f"prescribed.{name}"
    body, dof = _dof(where, t, bodies)
    kind = t["motion"]
    if kind not in MOTION_KINDS:
        raise ModelError(f"{where}.motion = {kind!r}: allowed: {', '.join(MOTION_KINDS)}")
    if kind in MOTION_PARSERS:
        return Prescribed(name, body, dof, kind, MOTION_PARSERS[kind](where, t))
    values = {}
    for k in MOTION_KINDS[kind]:
        default = 0.0 if k in ("start", "centre", "phase") else None
        v = t.get(k, default)
        if v is None:
            raise ModelError(f"{where}.{k}: missing (motion {kind!r} needs {', '.join(MOTION_KINDS[kind])})")
        values[k] = number(f"{where}.{k}", v, 0.0, strict_low=True) if k == "frequency" else number(f"{where}.{k}", v)
    for k in t:
        if k in {x for v in MOTION_KINDS.values() for x in v} and k not in MOTION_KINDS[kind]:
            raise ModelError(f"{where}.{k}: not a value of motion {kind!r}; allowed: {', '.join(MOTION_KINDS[kind])}")
    return Prescribed(name, body, dof, kind, values)


def _output(i: int, t: dict, model: Model) -> Output:
    where = _where("outputs", i, t)
    _fields(where, t, {"name", "kind", "body", "point", "component", "joint", "dof", "element", "term",
                       "source", "tolerance", "scale"}, ("kind",))
    name = _name(f"{where}.name", t.get("name", f"output{i}"))
    where = f"outputs.{name}"
    kind = t["kind"]
    if kind not in OUTPUT_KINDS:
        raise ModelError(f"{where}.kind = {kind!r}: allowed: {', '.join(OUTPUT_KINDS)}")
    common = dict(tolerance=number(f"{where}.tolerance", t.get("tolerance", 1e-3), 0.0, strict_low=True),
                  scale=number(f"{where}.scale", t.get("scale", 0.0), 0.0))
    names = {b.name for b in model.bodies}
    if kind == "coordinate":
        body, dof = _dof(where, t, model.bodies)
        return Output(name, kind, body=body, dof=dof, unit=model.coordinate_unit(body, dof), **common)
    if kind in ("point", "point_velocity", "point_acceleration"):
        body = _body_ref(f"{where}.body", t.get("body"), names)
        comp = t.get("component", "x")
        if comp not in COMPONENTS:
            raise ModelError(f"{where}.component = {comp!r}: allowed: x, y, z")
        return Output(name, kind, body=body, point=_vec(f"{where}.point", t.get("point", [0, 0, 0])),
                      component=COMPONENTS[comp], unit=POINT_UNITS[kind], **common)
    if kind == "force":
        el = {f.name: f for f in model.forces}
        if t.get("element") not in el:
            raise ModelError(f"{where}.element = {t.get('element')!r}: must name a force element; "
                             f"allowed: {', '.join(el) or '(none)'}")
        f = el[t["element"]]
        u = "N" if f.law.acts_on == POINTS else ("N m" if model.coordinate_unit(f.joint, f.dof) == "rad" else "N")
        return Output(name, kind, element=f.name, unit=u, component=plane_component(where, t, f), **common)
    if kind == "state":
        el = {f.name: f for f in model.forces}
        stateful = [f.name for f in model.forces if f.law.state is not None]
        if t.get("element") not in el or el[t["element"]].law.state is None:
            what = "is a force element whose law has no state" if t.get("element") in el else "must name a force element"
            raise ModelError(f"{where}.element = {t.get('element')!r}: {what}; allowed: the elements whose law has a "
                             f"state: {', '.join(stateful) or '(none)'}")
        f = el[t["element"]]
        return Output(name, kind, element=f.name, unit=f.law.state.unit, component=plane_component(where, t, f),
                      **common)
    if kind == "work":
        return Output(name, kind, **_work(where, t, model), unit="J", **common)
    if kind == "drive_force":
        pr = {p.name: p for p in model.prescribed}
        if t.get("element") not in pr:
            raise ModelError(f"{where}.element = {t.get('element')!r}: must name a prescribed motion; "
                             f"allowed: {', '.join(pr) or '(none)'}")
        p = pr[t["element"]]
        return Output(name, kind, element=p.name,
                      unit="N m" if model.coordinate_unit(p.joint, p.dof) == "rad" else "N", **common)
    term = t.get("term")
    if term not in ("kinetic", "gravity"):
        raise ModelError(f"{where}.term = {term!r}: allowed: kinetic, gravity")
    return Output(name, kind, term=term, unit="J", **common)


def _work(where: str, t: dict, model: Model) -> dict:
    """A work output's one load: ``element`` (a force element) or ``source`` (WORK_SOURCES)."""
    if ("element" in t) == ("source" in t):
        raise ModelError(f"{where}: give exactly one of element (a force element) or source "
                         f"({', '.join(WORK_SOURCES)})")
    elements = [f.name for f in model.forces]
    if "element" in t and t["element"] not in elements:
        raise ModelError(f"{where}.element = {t['element']!r}: must name a force element; allowed: "
                         f"{', '.join(elements) or '(none)'}")
    present = {"excitation": model.excitation is not None, "drive": bool(model.prescribed)}
    if "source" in t and not (isinstance(t["source"], str) and present.get(t["source"])):
        allowed = ", ".join(k for k in WORK_SOURCES if present[k]) or "(none: no [excitation], no [[prescribed]])"
        raise ModelError(f"{where}.source = {t['source']!r}: allowed: {allowed}")
    return {"element": t["element"]} if "element" in t else {"source": t["source"]}


def _initial(t, bodies, prescribed) -> dict:
    _fields("[initial]", t, {"coordinates", "velocities", "free"})
    out = {"initial_coordinates": {}, "initial_velocities": {}, "free": ()}
    by = {b.name: b for b in bodies}
    for key in ("coordinates", "velocities"):
        table = t.get(key, {})
        if not isinstance(table, dict):
            raise ModelError(f"[initial].{key} = {table!r}: must be a table of body = value (or [values])")
        for body, v in table.items():
            if body not in by:
                raise ModelError(f"[initial].{key}.{body}: unknown body; allowed: {', '.join(by)}")
            n = JOINT_DOFS[by[body].joint.type]
            vals = v if isinstance(v, list) else [v]
            if len(vals) != n:
                raise ModelError(f"[initial].{key}.{body} = {v!r}: must give {n} value(s), one per coordinate "
                                 f"of its {by[body].joint.type} joint")
            for k, x in enumerate(vals):
                x = number(f"[initial].{key}.{body}", x)
                if key == "coordinates" and abs(x) > MAX_COORDINATE:
                    raise ModelError(f"[initial].{key}.{body} = {v!r}: coordinate {k} must be within "
                                     f"+-{MAX_COORDINATE:g} (m or rad; beyond, a double cannot resolve its motion)")
                if (body, k) in prescribed:   # its motion gives its value: a value given must be that one
                    motion = prescribed[(body, k)]
                    at0 = float(motion(0.0)[0 if key == "coordinates" else 1])
                    if abs(x - at0) > 1e-12 * max(1.0, abs(at0)):
                        raise ModelError(f"[initial].{key}.{body} = {v!r}: coordinate {k} is prescribed "
                                         f"({motion.name}), whose motion gives {at0!r} at t = 0")
                    continue
                out[f"initial_{key}"][(body, k)] = x
    free = t.get("free", [])
    if not isinstance(free, list) or any(f not in by for f in free):
        raise ModelError(f"[initial].free = {free!r}: must be a list of body names (their joints' coordinates "
                         "are kept independent)")
    out["free"] = tuple((b, k) for b in free for k in range(JOINT_DOFS[by[b].joint.type]))
    return out


def angles_in_degrees(model: Model) -> list[str]:
    """One warning line per angle that looks like degrees (|value| > 2 pi): an initial coordinate of a
    turning coordinate (revolute, universal, spherical, a planar joint's turn), or a prescribed
    ``start``, ``amplitude`` or ``centre`` of one. Such a value is legal (a crank started ten turns on),
    so it is said, not refused."""
    out = []
    for (body, k), x in model.initial_coordinates.items():
        if model.coordinate_unit(body, k) == "rad" and abs(x) > TURN:
            n = JOINT_DOFS[model.body(body).joint.type]
            at = f"[{k}]" if n > 1 else ""
            out.append(f"[initial].coordinates.{body}{at} = {x:g}: looks like degrees; angles are in rad "
                       f"({x:g} deg = {math.radians(x):.6g} rad)")
    for p in model.prescribed:
        if "motion" in p.values or model.coordinate_unit(p.joint, p.dof) != "rad":
            continue
        for k in ("start", "amplitude", "centre"):
            x = p.values.get(k)
            if x is not None and abs(x) > TURN:
                out.append(f"prescribed.{p.name}.{k} = {x:g}: looks like degrees; angles are in rad "
                           f"({x:g} deg = {math.radians(x):.6g} rad)")
    return out
