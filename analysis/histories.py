"""A run's histories as report items (issue 24: moved from workflows/report.py): every
recovered history of a case as an :class:`~.tables.Item` (posts, recoveries, net c.g. load
factors, output points, tank pressures and ullage volumes), the attach points' interface
histories, the liquids' heads under gravity and the twang of the stack's top. Duck-typed
on liftoff's TransientResult and case problem (nothing imported from them); SI units.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from liftoff.core.labels import TRANSLATIONS, point_labels
from liftoff.core.units import G0        # standard gravity: load factors are in units of it

from .tables import Item


def items(result, attach: dict, heads: dict | None = None, band_hz: float = 0.0) -> list[Item]:
    """Every reported history: post forces, recovered items (attach forces, c.g. motion; not
    the modal coordinates), output points, and with ``heads`` (:func:`liquid_heads`) the
    total tank pressures and ullage volumes. Names, units and kinds come from the result's
    contact directions and recovery items; ``attach``: recovery name -> (point, component).
    ``band_hz`` > 0: the acceleration-type histories low-pass filtered to that band
    (analysis/spectra.lowpass; ``[postprocess] acceleration_band_hz``), the unfiltered
    history kept as ``raw``: the output-point accelerations and every recovery made from
    the modal accelerations alone (``RecoveryItem.from_acceleration``: liquid pressures,
    liquid inertia forces, a Nastran ATM), whose peaks are set by the highest modes."""
    from liftoff.analysis.spectra import lowpass

    out = []
    for j, d in enumerate(result.contact_directions):
        out.append(Item(f"post {d.contact} {d.component}", d.unit, result.contact_force[:, j], "contact_force"))
    for it in result.recovery_items.values():
        if it.category == CG_ACCELERATION:
            out += load_factor_items(result, it, band_hz)
            continue
        if it.category == "modal":
            continue
        arr = result.recovered[it.name]
        head = it.name
        if it.category == "interface_force" and it.name in attach:
            point, comp = attach[it.name]
            head = f"attach {point} on {comp}"
        band = band_hz if it.from_acceleration else 0.0
        filtered = lowpass(arr, result.h, band)
        for j, (lab, unit) in enumerate(zip(it.labels, it.units)):
            out.append(Item(f"{head} {lab}", unit, filtered[:, j], it.category, raw=arr[:, j] if band > 0 else None))
    dunits, aunits = result.output_units("a", "disp"), result.output_units("a", "acc")
    for j, lab in enumerate(result.output_labels["a"]):
        out.append(Item(f"disp {lab}", dunits[j], result.displacement["a"][:, j], "displacement"))
        acc = result.acceleration["a"][:, j]
        out.append(Item(f"acc {lab}", aunits[j], lowpass(acc, result.h, band_hz), "acceleration",
                        raw=acc if band_hz > 0 else None))
    if heads is not None:
        out += tank_items(result, heads, band_hz)
    return out


#: the span at each end of a record, in periods of the band's cutoff (2 / f_c s), where a
#: filtered history's zero-phase filter (spectra.lowpass) carries its end transient: a sine
#: ending anywhere in its period came out up to 5-30 % high there (35 Hz in a 40 Hz band)
EDGE_PERIODS = 2.0


def edge_extremes(time: np.ndarray, its: list[Item], band_hz: float) -> list[tuple[str, str, float]]:
    """(item, 'max' | 'min', t) of each band-limited item (``raw`` kept: :func:`items` with
    ``band_hz`` > 0) whose max or min lies within EDGE_PERIODS / ``band_hz`` s of either end of
    the record, where the filter's end transient may have made or raised it."""
    if not band_hz > 0 or time.size < 2:
        return []
    edge = EDGE_PERIODS / band_hz
    near = lambda k: time[k] - time[0] < edge or time[-1] - time[k] < edge  # noqa: E731
    out = []
    for it in its:
        if it.raw is None:
            continue
        for side, k in (("max", int(np.argmax(it.values))), ("min", int(np.argmin(it.values)))):
            if near(k):
                out.append((it.name, side, float(time[k])))
    return out


def item_categories(problem) -> set[str]:
    """The categories of the items :func:`items` makes of the result of ``problem`` (a
    TransientProblem, duck-typed: its contacts, recoveries and body a's output points),
    known before it is solved, so that a selection by category ([postprocess.srs] /
    [postprocess.psd]) can be checked before any case runs. The tank items (``heads``)
    are not counted: no selection by category reaches them."""
    cats = {"contact_force"} if any(len(c.labels_a) for c in problem.contacts) else set()
    for r in problem.recoveries:
        if r.category != "modal":
            cats.add("cg_load_factor" if r.category == CG_ACCELERATION else r.category)
    if problem.outputs.get("a"):
        cats |= {"displacement", "acceleration"}
    return cats


#: recovery category of a vehicle component's net c.g. acceleration (reduction.cg_acceleration_recovery,
#: workflows/loads.recoveries): the reports turn it into the net c.g. load factor (:func:`load_factor_items`)
CG_ACCELERATION = "cg_acceleration"


def load_factor_items(result, it, band_hz: float = 0.0) -> list[Item]:
    """A component's net c.g. load factor (g) from its c.g. acceleration item (category
    ``cg_acceleration``, m/s^2; reduction.cg_acceleration_recovery): n = (a - g) / g0 with g the
    run's gravity field (result metadata), the specific force of the component's c.g.: the net
    non-gravity force on it over its weight, +1 g upward (z) at rest on the pad. An
    acceleration-type history: band-limited like the other accelerations (``band_hz``)."""
    from liftoff.analysis.spectra import lowpass

    comp = it.name.removeprefix("cg_accel_")
    gvec = np.asarray(result.metadata.get("gravity", (0.0, 0.0, 0.0)), dtype=float)
    a = result.recovered[it.name]
    n = (a - gvec[None, :]) / G0
    filtered = lowpass(n, result.h, band_hz)
    return [Item(f"load factor {comp} N{lab[-1].lower()}", "g", filtered[:, j], "cg_load_factor",
                 raw=n[:, j] if band_hz > 0 else None) for j, lab in enumerate(it.labels)]


def interface_histories(result, attach: dict) -> list:
    """The attach points' load histories as analysis.interface_loads.InterfaceHistory, named as
    the max/min rows name them (``attach <point> on <component>``); ``attach``: recovery name
    -> (point, component)."""
    from liftoff.analysis.interface_loads import InterfaceHistory

    out = []
    for it in result.recovery_items.values():
        if it.category == "interface_force" and it.name in attach:
            point, comp = attach[it.name]
            out.append(InterfaceHistory(f"attach {point} on {comp}", tuple(it.labels), tuple(it.units),
                                        result.recovered[it.name]))
    return out


LIQUID_PRESSURE, ULLAGE = "_liquid_pressure", "_ullage_volume"     # component recovery names end so


def liquid_heads(cp) -> dict[str, np.ndarray]:
    """{recovery name: head (Pa) per column} of the liquids' pressure items: the pressure
    rows (over the vehicle's modes) times the modal acceleration of a uniform acceleration
    -g, Phi^T M RB (-g) (eq. 14; exact for the rigid-body part, which is all a uniform field
    has): the hydrostatic head under gravity, which the total tank pressure adds to the
    dynamic pressure from the accelerations (reduction.liquid)."""
    pr = cp.problem
    g = np.asarray(pr.forcing.gravity, float).reshape(-1)[:3]
    out = {}
    for r in pr.recoveries:
        if r.name.endswith(LIQUID_PRESSURE) and r.acc is not None and r.body == "a":
            out[r.name] = r.acc @ pr.body_a.modal_gravity(-g)
    return out


def tank_items(result, heads: dict, band_hz: float = 0.0) -> list[Item]:
    """Total tank pressure (dynamic + head) and ullage volume change histories; ``band_hz``
    > 0: the dynamic pressure (from the accelerations) in that band, as in :func:`items`."""
    from liftoff.analysis.spectra import lowpass

    out = []
    for it in result.recovery_items.values():
        if it.name in heads:
            dynamic, head = result.recovered[it.name], heads[it.name]
            band = band_hz if it.from_acceleration else 0.0
            arr = lowpass(dynamic, result.h, band) + head
            raw = dynamic + head if band > 0 else None
            out += [Item(f"tank pressure {lab}", "Pa", arr[:, j], "tank_pressure", raw=None if raw is None else raw[:, j])
                    for j, lab in enumerate(it.labels)]
        elif it.name.endswith(ULLAGE):
            arr = result.recovered[it.name]
            out += [Item(f"ullage volume change {lab}", "m^3", arr[:, j], "ullage_volume")
                    for j, lab in enumerate(it.labels)]
    return out


def release_time(cp) -> float | None:
    """The first hold-down release (booster ignition in the lift-off scenario), None if none."""
    rel = [p.release_time for p in cp.case.posts if np.isfinite(p.release_time)]
    return min(rel) if rel else None


@dataclass
class Twang:
    """Lateral (x, y) motion of the recovery's ``top`` point (the tank tip), m.

    ``pad``: in the pad frame (the pad's foundation is the ground), from its position at t0
    (the static state on the pad before main-engine start): the twang as engineers quote
    it. ``rel_cg``: the top's lateral displacement less the c.g.'s (eq. 23), as before.
    Peaks are taken before the first hold-down release ``t_ign`` (the whole run without
    one); ``at_ign``: the pad-frame twang at ``t_ign``, interpolated in time."""

    point: str
    time: np.ndarray
    pad: np.ndarray
    rel_cg: np.ndarray
    t_ign: float | None

    def _peak(self, xy: np.ndarray) -> int:
        n = self.time.size if self.t_ign is None else max(int(np.searchsorted(self.time, self.t_ign, "right")), 1)
        return int(np.argmax(np.hypot(xy[:n, 0], xy[:n, 1])))

    @property
    def i_peak(self) -> int:
        return self._peak(self.pad)

    @property
    def i_peak_cg(self) -> int:
        return self._peak(self.rel_cg)

    @property
    def at_ign(self) -> np.ndarray | None:
        if self.t_ign is None or not self.time[0] <= self.t_ign <= self.time[-1]:
            return None
        return np.array([np.interp(self.t_ign, self.time, self.pad[:, j]) for j in range(2)])

    def line(self) -> str:
        """One summary line: pad-frame peak and value at the first hold-down release (the
        Shuttle's booster ignition), relative-to-c.g. peak."""
        i, k = self.i_peak, self.i_peak_cg
        peak = float(np.hypot(*self.pad[i]))
        out = (f"twang at {self.point} (pad frame, from t0): peak {peak:.3f} m at t = {self.time[i]:.2f} s "
               f"(x {self.pad[i, 0]:+.3f}, y {self.pad[i, 1]:+.3f} m)")
        ign = self.at_ign
        if ign is not None:
            v = float(np.hypot(*ign))
            out += (f"; at hold-down release (t = {self.t_ign:.2f} s) {v:.3f} m"
                    + (f" = {100 * v / peak:.0f} % of the peak" if peak > 0 else ""))
        # (eq. 23's measure is from the undeformed stack, not from t0 as the pad frame's: the preloads'
        # static lean at t0 is in it, and said)
        return out + (f"; relative to the c.g. (eq. 23, from the undeformed stack, {float(np.hypot(*self.rel_cg[0])):.3f}"
                      f" m at t0): peak {float(np.hypot(*self.rel_cg[k])):.3f} m at t = {self.time[k]:.2f} s")


def twang(result, cp) -> Twang | None:
    """The twang of a lift-off case (None without a ``[recovery] top`` point)."""
    top = cp.case.recovery.top
    if not top:
        return None
    labels = result.output_labels["a"]
    cg_item = result.items("cg_motion")[0]
    cg = result.recovered[cg_item.name][:, _translations(cg_item)[:2]]
    u = result.displacement["a"][:, [labels.index(lab) for lab in point_labels(top, TRANSLATIONS[:2])]]
    return Twang(top, result.time, u - u[0], u - cg, release_time(cp))


def _translations(item) -> list[int]:
    """Columns of a recovery item labelled with a translation component (Tx Ty Tz), in order."""
    return [item.labels.index(c) for c in TRANSLATIONS if c in item.labels]
