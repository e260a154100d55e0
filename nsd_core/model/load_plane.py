"""The model file's fields of a plane law's element (nsd_core.model.laws.PLANE; docs/models.md): its
``dofs`` and the ``component`` of its force and state outputs, checked as every field is (one line
naming the element, the field, the value and what is allowed: ModelError, exit 2)."""
from __future__ import annotations

from nsd_core.model.description import COMPONENTS, Body
from nsd_core.model.errors import ModelError
from nsd_core.model.laws import PLANE


def plane_dofs(where: str, dofs, body: Body) -> tuple[int, int]:
    """``dofs`` of a plane element on ``body``'s joint: two different slide coordinates (x, y)."""
    slides = [k for k, (kind, _) in enumerate(body.joint.dofs()) if kind == "P"]
    if (not isinstance(dofs, list) or len(dofs) != 2 or any(type(k) is not int or k not in slides for k in dofs)
            or dofs[0] == dofs[1]):
        raise ModelError(f"{where}.dofs = {dofs!r}: must be two different slide coordinates of {body.name}'s "
                         f"{body.joint.type} joint (x, y); its slides: {slides or 'none'}")
    return dofs[0], dofs[1]


def plane_component(where: str, t: dict, f) -> int:
    """A force or state output's component: of a plane law's element, x (its first coordinate) or y;
    no other element has components."""
    if f.law.acts_on != PLANE:
        if "component" in t:
            raise ModelError(f"{where}.component = {t['component']!r}: element {f.name!r} has one value (no components)")
        return 0
    comp = t.get("component")
    if comp not in ("x", "y"):
        raise ModelError(f"{where}.component = {comp!r}: allowed: x, y (element {f.name!r} acts on the plane "
                         f"of {f.joint}'s coordinates {list(f.dofs)})")
    return COMPONENTS[comp]
