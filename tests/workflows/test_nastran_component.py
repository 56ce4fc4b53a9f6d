"""A `liftoff run` component from a Nastran Craig-Bampton model: the stick model's orbiter
written as a DMIG punch in inch-pound-second units (reduction.nastran.write_dmig), read
back through the scenario's [model.component.orbiter.nastran], gives the same vehicle
and the same loads as the orbiter reduced in liftoff. Tolerance: the punch keeps 10
significant digits (large-field DMIG: each entry within eps = 5e-10 of itself), so a
system frequency moves by at most its first-order perturbation bound, 0.5 eps (|t|^T |K|
|t| + lambda |t|^T |M| |t|) / lambda over the orbiter's rows t of the mode (1e-9 added
for the eigensolver): ~1e-9 for most modes, but 2.8e-6 for the stick's first (0.81 Hz),
in which the orbiter swings almost rigidly on its statically determinate bipods, so its
strain energy is a small difference of large entries (measured 4.4e-7; 1.5e-9 the next
largest). Post forces agree to 1e-7."""
import tomllib

import numpy as np
import pytest

from liftoff.config import Where, default_text, parse_scenario
from liftoff.core.errors import InputError
from liftoff.workflows.cache import StageCache
from liftoff.workflows.loads import build_problem
from liftoff.workflows.pipeline import build_stack

from .test_run import STICK

pytest.importorskip("pyyeti.nastran")


def _case(model, tmp_path):
    d = tomllib.loads(default_text())
    d["model"] = model
    d["time"]["t_end"] = 7.2
    d["case"] = [{"name": "nominal"}]
    return parse_scenario(d, "s.toml", tmp_path).cases[0]


def test_orbiter_from_a_dmig_punch_in_inch_pound(tmp_path):
    from liftoff.reduction.nastran import write_dmig
    from liftoff.transient import solve

    cache = StageCache(tmp_path / "cache")
    case = _case(STICK, tmp_path)
    stack = build_stack(case.model, cache, progress=False, where=Where("s.toml", "model"))
    orbiter = stack.cbs["orbiter"]
    ids = {p: 101 + k for k, p in enumerate(orbiter.boundary_points)}
    write_dmig(orbiter, tmp_path / "orbiter.pch", units="in-lbf-s", grid_ids=ids)
    model = {**STICK, "component": {"orbiter": {"f_max": 60.0, "nastran": {
        "file": "orbiter.pch", "units": "in-lbf-s", "grids": {str(g): p for p, g in ids.items()}}}}}
    case2 = _case(model, tmp_path)
    stack2 = build_stack(case2.model, cache, progress=False, where=Where("s.toml", "model"))
    assert stack2.cbs["orbiter"].source_units.startswith("in-lbf-s") and "orbiter" not in stack2.components
    f1, f2 = stack.vehicle.omega[6:], stack2.vehicle.omega[6:]
    asm, sysm, lam = stack.vehicle_asm, stack.vehicle_modes, stack.vehicle.omega[6:] ** 2
    cb = asm.component("orbiter")
    t = np.abs(sysm.phi[asm.cb_index("orbiter")][:, 6:])
    K, M = np.abs(cb.K), np.abs(cb.M)             # a CBModel's matrices are dense
    bound = 0.5 * 5e-10 * (np.einsum("ik,ij,jk->k", t, K, t) + lam * np.einsum("ik,ij,jk->k", t, M, t)) / lam
    assert f1.size == f2.size and np.all(np.abs(f2 / f1 - 1) <= bound + 1e-9)
    assert np.median(bound) < 1e-8            # the bound is loose only where the energy cancels
    assert abs(stack2.vehicle.mass / stack.vehicle.mass - 1) < 1e-9
    r1, r2 = (solve(build_problem(c, s, progress=False).problem) for c, s in ((case, stack), (case2, stack2)))
    peak = np.abs(r1.contact_force).max()
    assert np.abs(r2.contact_force - r1.contact_force).max() < 1e-7 * peak
    assert np.array_equal(np.isnan(r1.separation_time), np.isnan(r2.separation_time))


def test_bad_nastran_component_is_one_line(tmp_path):
    for nastran, expect in (({"file": "none.pch", "units": "SI"}, "nastran.file: file not found"),
                            ({"units": "SI"}, "missing required key 'file'"),
                            ({"file": "s.toml", "units": "furlong-firkin"}, "nastran.units: unknown unit system"),
                            ({"file": "s.toml", "units": "SI", "grids": {"x": "a"}}, "is not a grid ID"),
                            # (str.isdigit takes a superscript two; int() did not: a ValueError)
                            ({"file": "s.toml", "units": "SI", "grids": {"\u00b2": "a"}}, "is not a grid ID"),
                            ({"file": "s.toml", "units": "SI", "grids": {"1": "a", "01": "b"}},
                             "is not a grid ID|given twice"),
                            ({"file": "s.toml", "units": "SI", "grids": [{"1": "a"}]}, "grids: expected a table"),
                            ({"file": "a\x00b", "units": "SI"}, "nastran.file: not a usable file name"),
                            # recovery items: checked when read (disp = 1 was an AttributeError at the build)
                            ({"file": "s.toml", "units": "SI", "recovery": [{"name": "r", "disp": 1}]},
                             r"recovery\[0\]\.disp: expected a string"),
                            ({"file": "s.toml", "units": "SI", "recovery": [{"name": "r"}]},
                             "give at least one of disp, vel, acc"),
                            ({"file": "s.toml", "units": "SI", "recovery": [{"name": "r", "acc": "a"},
                                                                           {"name": "r", "acc": "b"}]},
                             "duplicate recovery item name 'r'")):
        (tmp_path / "s.toml").write_text("")
        with pytest.raises(Exception, match=expect) as e:
            _case({**STICK, "component": {"orbiter": {"nastran": nastran}}}, tmp_path)
        assert "\n" not in str(e.value) and "model.component.orbiter.nastran" in str(e.value)


def test_grid_maps_that_would_disconnect_are_refused(tmp_path):
    """Issue 27: a grid map naming a misspelt attach point left the orbiter's forward
    attach silently disconnected; grid IDs absent from the file were ignored."""
    from liftoff.reduction.nastran import write_dmig

    cache = StageCache(tmp_path / "cache")
    stack = build_stack(_case(STICK, tmp_path).model, cache, progress=False, where=Where("s.toml", "model"))
    ids = {p: 101 + k for k, p in enumerate(stack.cbs["orbiter"].boundary_points)}
    write_dmig(stack.cbs["orbiter"], tmp_path / "orbiter.pch", units="in-lbf-s", grid_ids=ids)
    grids = {str(g): p for p, g in ids.items()}

    def build(grids):
        model = {**STICK, "component": {"orbiter": {"f_max": 60.0, "nastran": {
            "file": "orbiter.pch", "units": "in-lbf-s", "grids": grids}}}}
        return build_stack(_case(model, tmp_path).model, cache, progress=False, where=Where("s.toml", "model"))

    typo = {g: ("att_orb_fwdd" if p == "att_orb_fwd" else p) for g, p in grids.items()}
    with pytest.raises(InputError, match=r"s\.toml: model\.component\.orbiter\.nastran\.grids: no grid is named "
                                         r"'att_orb_fwd', a joint of orbiter with the stack"):
        build(typo)
    with pytest.raises(InputError, match=r"grid_names: grid 999 is not a boundary grid of the file"):
        build({**grids, "999": "somewhere"})
