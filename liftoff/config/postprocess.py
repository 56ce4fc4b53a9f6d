"""``[postprocess]``: the loads post-processing of a ``liftoff run`` (scenario level, not per case).

* ``uncertainty``: a factor per recovery category (``interface_force = 1.25`` ...) applied to
  the envelope and statistical loads in design_loads.csv;
* ``[postprocess.srs]``: shock response spectra (absolute acceleration, Q values ``q``,
  ``n_freq`` frequencies log-spaced from ``f_min`` to ``f_max`` Hz) of the items of the
  ``categories`` named (default: acceleration);
* ``[postprocess.psd]``: Welch PSD (segments of ``segment`` s) and FFT amplitude of the
  items of ``categories``, for the cases whose histories are kept;
* ``[postprocess.fields]``: ParaView output of the governing case: ``frames`` deformed
  shapes of stack and pad as a .pvd series of .vtu files and an animated GIF (``gif``);
* ``acceleration_band_hz``: the band (Hz) the acceleration-type histories of the max/min
  tables, envelopes and statistics are low-pass filtered to (0: unfiltered): the output-point
  accelerations and every recovery made from the accelerations alone (liquid and tank
  pressures, liquid inertia forces, a Nastran ATM). Their peaks are set by the highest modes,
  which a Craig-Bampton model does not converge (issue 22: 10x between component cuts);
  within the band where its system modes are converged they are. SRS and PSD use the
  unfiltered histories;
* ``units``: the unit system of the workbook loads.xlsx, ``"SI"`` (default) or ``"in-lbf-s"``
  (analysis.units: lbf, lbf in, in, in/s^2, psi); the CSV and HDF5 files stay SI.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .values import Where, boolean, integer, number, strings, table

CATEGORIES = ("contact_force", "interface_force", "cg_motion", "displacement", "acceleration")
KEYS = {"uncertainty", "srs", "psd", "fields", "acceleration_band_hz", "units"}
UNITS = ("SI", "in-lbf-s")     # [postprocess] units: the workbook's (analysis.units); CSV and HDF5 stay SI
ACCELERATION_BAND_HZ = 40.0   # the default model's components to 60 Hz: the filter passes < 0.2 % there
SRS_KEYS = {"categories", "q", "f_min", "f_max", "n_freq"}
PSD_KEYS = {"categories", "segment"}
FIELDS_KEYS = {"enabled", "frames", "gif"}


@dataclass(frozen=True)
class SRSSpec:
    categories: tuple[str, ...] = ("acceleration",)
    q: tuple[float, ...] = (10.0,)
    f_min: float = 1.0
    f_max: float = 50.0
    n_freq: int = 60


@dataclass(frozen=True)
class PSDSpec:
    categories: tuple[str, ...] = ("acceleration",)
    segment: float = 2.0


@dataclass(frozen=True)
class FieldsSpec:
    enabled: bool = False
    frames: int = 48
    gif: bool = True


@dataclass(frozen=True)
class PostProcess:
    uncertainty: dict = field(default_factory=dict)
    srs: SRSSpec | None = None
    psd: PSDSpec | None = None
    fields: FieldsSpec = FieldsSpec()
    acceleration_band_hz: float = ACCELERATION_BAND_HZ
    units: str = "SI"


def _categories(where: Where, value: Any) -> tuple[str, ...]:
    cats = strings(where, value if isinstance(value, list) else [value], nonempty=True)
    for i, c in enumerate(cats):
        if c not in CATEGORIES:
            raise (where / i).error(f"unknown category {c!r} (categories: {', '.join(CATEGORIES)})")
    return cats


def postprocess(where: Where, spec: Any) -> PostProcess:
    p = table(where, spec, KEYS)
    uf = table(where / "uncertainty", p.get("uncertainty", {}), set(CATEGORIES))
    unc = {k: number(where / "uncertainty" / k, v, positive=True) for k, v in uf.items()}
    for k, f in unc.items():          # (it widens the design range: analysis.aggregate.factored_outward)
        if not f >= 1.0:
            raise (where / "uncertainty" / k).error(f"an uncertainty factor is at least 1, got {f:g} (it widens the "
                                                    "design range; 1.25 is 25 % on the loads)")
    srs = None
    if "srs" in p:
        w = where / "srs"
        s = table(w, p["srs"], SRS_KEYS)
        q = s.get("q", [10.0])
        q = tuple(number(w / "q" / i, x, positive=True) for i, x in enumerate(q if isinstance(q, list) else [q]))
        f0, f1 = number(w / "f_min", s.get("f_min", 1.0), positive=True), number(w / "f_max", s.get("f_max", 50.0))
        if not f1 > f0:
            raise (w / "f_max").error(f"must be greater than f_min = {f0:g} Hz, got {f1:g}")
        srs = SRSSpec(_categories(w / "categories", s.get("categories", ["acceleration"])), q, f0, f1,
                      integer(w / "n_freq", s.get("n_freq", 60), 2, 100_000))
    psd = None
    if "psd" in p:
        w = where / "psd"
        s = table(w, p["psd"], PSD_KEYS)
        psd = PSDSpec(_categories(w / "categories", s.get("categories", ["acceleration"])),
                      number(w / "segment", s.get("segment", 2.0), positive=True))
    w = where / "fields"
    f = table(w, p.get("fields", {}), FIELDS_KEYS)
    fields = FieldsSpec(boolean(w / "enabled", f.get("enabled", False)), integer(w / "frames", f.get("frames", 48), 2,
                                                                                   10_000),
                        boolean(w / "gif", f.get("gif", True)))
    band = number(where / "acceleration_band_hz", p.get("acceleration_band_hz", ACCELERATION_BAND_HZ), nonneg=True)
    units = p.get("units", "SI")
    if units not in UNITS:
        raise (where / "units").error(f"must be one of {', '.join(map(repr, UNITS))} (the workbook's units; the CSV "
                                      f"and HDF5 files stay SI), got {units!r}")
    return PostProcess(unc, srs, psd, fields, band, units)
