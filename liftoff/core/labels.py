"""DOF labels and point names, the handles every stage uses for physical DOFs.

A DOF is named ``point:component``, component one of ``Tx Ty Tz Rx Ry Rz`` (translations
in m, small rotations in rad), e.g. ``srb_left_hd_1:Tz``.

A point is *named* (a user's handle: an interface, a hold-down, an engine mount, a
recovery station) unless it is an automatic node name ``<owner>_n<k>`` of a stick
model. Named points are the Craig-Bampton boundary points of a component and the only
points a scenario may refer to.
"""
from __future__ import annotations

import re

from .errors import InputError

COMPONENTS = ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")
TRANSLATIONS = COMPONENTS[:3]
_LABEL = re.compile(r"^[^:\s]+:(Tx|Ty|Tz|Rx|Ry|Rz)$")
_AUTO_NODE = re.compile(r"^.+_n\d+$")


def split_label(label: str) -> tuple[str, int]:
    """``'post_1:Tz'`` -> ``('post_1', 2)``; InputError on a malformed label."""
    if not isinstance(label, str) or not _LABEL.match(label):
        raise InputError(f"malformed DOF label {label!r}: expected 'point:Tx|Ty|Tz|Rx|Ry|Rz'")
    point, comp = label.split(":")
    return point, COMPONENTS.index(comp)


def point_labels(point: str, components=COMPONENTS) -> list[str]:
    """``point:Tx`` ... for the given components (default all six)."""
    return [f"{point}:{c}" for c in components]


def points_labels(points, components=COMPONENTS) -> list[str]:
    """The labels of several points, point-major."""
    return [lab for p in points for lab in point_labels(p, components)]


def is_named_point(name: str) -> bool:
    """False for a stick model's automatic node name ``<owner>_n<k>``, True otherwise."""
    return not _AUTO_NODE.match(name)


def named_points(points) -> list[str]:
    """The named points among ``points`` (see :func:`is_named_point`), in order."""
    return [p for p in points if is_named_point(p)]
