"""A change of a peak between two load cycles split into what caused it (issue 24): the
forcing, the modes and the damping, by re-running the transient with one of them swapped
at a time (workflows/contributions.py runs them; this module does the arithmetic).

The states, each an envelope of max/min rows (item, unit, max, min):

0. the earlier cycle rebuilt now: its scenario on today's code;
1. the new scenario's cases (forcing, times, contacts, control) on the earlier model;
2. the new cases on the new model, with the earlier damping;
3. the new run.

With the earlier run's own peak ``old`` (its max/min file), a peak's change is the sum
(old -> 0) + (0 -> 1) + (1 -> 2) + (2 -> 3) = other + forcing + modes + damping: the parts
telescope, so they add up to the change exactly (to the round-off of three subtractions).
``other`` is what the rebuilt earlier cycle does not reproduce of the earlier run: code,
files or cases changed since (zero when nothing did). The split is sequential (forcing
first, then modes, then damping): where two changes interact, the interaction goes to the
later one, as in any one-at-a-time attribution; the file says so. numpy only.
"""
from __future__ import annotations

import numpy as np

PARTS = ("other", "forcing", "modes", "damping")
FIELDS = ("item", "unit", "side", "old", "old_rebuilt", "other", "forcing", "modes", "damping", "new", "change")


def split(old: dict[str, dict], states: list[list[dict]]) -> list[dict]:
    """Rows of the split: per item present in the earlier run (``old``: item -> {max, min,
    unit}) and in the four ``states`` (:data:`PARTS` order, each a list of envelope rows),
    one row per side (max, min) with the parts and the change new - old."""
    if len(states) != 4:
        raise ValueError("split: four states (rebuilt earlier, new forcing, new modes, new run)")
    by = [{r["item"]: r for r in rows} for rows in states]
    out = []
    for item, o in old.items():
        if not all(item in b for b in by):
            continue
        for side in ("max", "min"):
            v = [float(o[side])] + [float(b[item][side]) for b in by]
            parts = np.diff(v)
            out.append({"item": item, "unit": by[3][item].get("unit", o.get("unit", "")), "side": side,
                        "old": v[0], "old_rebuilt": v[1], **dict(zip(PARTS, parts.tolist())), "new": v[4],
                        "change": v[4] - v[0]})
    return out
