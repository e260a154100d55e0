"""Random valid mechanism descriptions (the format of docs/models.md), for differential testing.

``generate(draws)`` returns a description as the dict a TOML file holds (one ``[[case]]`` included);
``draws`` supplies every random choice (``Draws(seed)``: numpy's seeded generator; a test may pass an
adapter over hypothesis's ``data.draw`` to get shrinking). Four families:

- ``open_chain``: 1-6 bodies in a tree, every joint type of the format, random products of inertia,
  springs on slides (so nothing drifts away), point springs, ropes, stops, the device's stateful
  laws, a plane hysteresis on a planar joint, a constant force, a harmonic drive, gravity, a ground
  excitation;
- ``four_bar``: every Grashof class (crank-rocker, double-crank, double-rocker, non-Grashof) on either
  assembly branch, in a plane of any orientation, driven at constant speed, driven harmonically or free;
- ``slider_crank``: with an offset, driven or free;
- ``spatial_rssr``: a spatial four-bar (revolute-spherical-spherical-revolute), driven harmonically.

Physically sensible by construction: link proportions are drawn, then the motion is screened before
the description is kept, by the same closed-form kinematics that drew them (no engine involved):
every closed loop keeps its transmission angle (four-bar, slider-crank) or its closure's sensitivity
(RSSR) at least ``MARGIN`` away from a singular position over the whole input range it will travel
(a full turn for a crank, the harmonic drive's arc otherwise; a free crank may turn either way, so
the full turn is screened). Proportions that fail are drawn again. The initial coordinates of a
loop are the exact assembly on the drawn branch, perturbed by at most 0.02 rad, so the shared
start-up Newton lands on that branch. Open chains keep initial angles within 0.3 rad and rates within
1-2 rad/s (a spherical joint's Euler angles stay far from their singular middle angle of +-90 deg over
the case's duration), and every slide has a spring (nothing drifts out of reach).
"""
from __future__ import annotations

from comparisons.campaign.chains import open_chain
from comparisons.campaign.loops import four_bar, slider_crank, spatial_rssr
from comparisons.campaign.parts import Draws  # noqa: F401 (the seeded source, with the generator)

FAMILIES = ("open_chain", "four_bar", "slider_crank", "spatial_rssr")


def generate(draws, family: str | None = None) -> dict:
    """One random description (a dict as its TOML file holds it) of ``family`` (drawn if None)."""
    family = family or draws.choice(FAMILIES)
    return {"open_chain": open_chain, "four_bar": four_bar, "slider_crank": slider_crank,
            "spatial_rssr": spatial_rssr}[family](draws)
