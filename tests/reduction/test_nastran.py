"""Craig-Bampton components from Nastran (reduction/nastran.py) against Nastran's own output
and pyyeti (tests/data/nastran/README.md: an NX Nastran 9 run of two EXTSEOUT components,
inboard and outboard, and of their assembly; units mm-kg-s).

References: the system eigenvalues Nastran printed for the assembly (assemble.out) and
wrote in double precision (nas2cam lambda), Nastran's system modes on the inboard a-set
(nas2cam ULVS), Nastran's weight check, pyyeti's cbcheck, cbconvert and uset_convert, and
closed-form frame rotations.
"""
from __future__ import annotations

import io
import math
import re
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from liftoff.core.errors import InputError
from liftoff.reduction import (CBModel, assemble, cb_check, component_recovery, displacement_recovery, load_cb,
                               system_modes)
from liftoff.reduction.nastran import (LBF, NastranRecovery, from_dmig, from_extseout, from_nas2cam, import_nastran,
                                       unit_system, write_dmig)

pytest.importorskip("pyyeti.nastran")      # installed by `make setup`; a missing one names itself here
from pyyeti import cb as pcb                           # noqa: E402
from pyyeti.nastran import bulk, n2p, op2, op4        # noqa: E402

from ..roundoff import sum_rtol

DATA = Path(__file__).resolve().parents[1] / "data" / "nastran"
MM = "mm-kg-s"                   # the units of the test model (tests/data/nastran/README.md)
SLINCH = LBF / 0.0254            # kg per lbf s^2/in


def extseout(stem: str, **kw) -> CBModel:
    return from_extseout(DATA / f"{stem}.op4", name=stem, units=kw.pop("units", MM), **kw)


@pytest.fixture(scope="module")
def parts():
    rec = [NastranRecovery("grid_disp", disp="mug1"), NastranRecovery("bar_forces", disp="mef1", quantity="force")]
    return extseout("inboard", recovery=rec), extseout("outboard")


@pytest.fixture(scope="module")
def system(parts):
    inboard, outboard = parts
    asm = assemble([outboard, inboard], "assembly")
    return asm, system_modes(asm)


@pytest.fixture(scope="module")
def nas2cam():
    return op2.rdnas2cam(str(DATA / "nas2cam"))


def printed_frequencies(path: Path) -> np.ndarray:
    """The CYCLES column of the (only) real eigenvalue table of a Nastran .out file."""
    text = path.read_text()
    table = text[text.index("R E A L   E I G E N V A L U E S"):]
    rows = re.findall(r"^\s+(\d+)\s+\d+\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$", table, flags=re.M)
    out, expect = [], 1
    for r in rows:
        if int(r[0]) != expect:
            break
        out.append(float(r[3]))
        expect += 1
    return np.array(out)


# ---------------------------------------------------------------- the assembled system
def test_system_frequencies_match_nastran(system, nas2cam):
    asm, sysm = system
    f_out = printed_frequencies(DATA / "assemble.out")
    assert f_out.size == 54 == sysm.n_modes            # 24 boundary + 8 + 22 modal DOFs
    # Nastran assembled the very same matrices, so every elastic mode agrees up to the
    # 7 significant digits of the print (rounding <= 5e-7 relative); measured 4.7e-7.
    rel = np.abs(sysm.freq_hz[6:] / f_out[6:] - 1)
    assert rel.max() < 1e-6
    below_cutoff = f_out[6:] < 50.0                    # EIGRL V2 = 50 Hz in both component runs
    assert below_cutoff.sum() == 19 and rel[below_cutoff].max() < 1e-4    # the criterion
    # nas2cam's eigenvalues (written as single-precision reals: 6e-8 relative) : measured 2.5e-8
    f_n2c = np.sqrt(np.abs(nas2cam["lambda"][0])) / (2 * np.pi)
    assert np.allclose(sysm.freq_hz[6:], f_n2c[6:], rtol=2e-7)
    assert np.all(sysm.freq_hz[:6] == 0) and f_out[:6].max() < 1e-4      # Nastran's rigid modes: noise


def test_recovery_through_system_modes_matches_nastran_ulvs(parts, system, nas2cam):
    """MUG1 recovered through liftoff's system modes equals MUG1 @ ULVS (Nastran's own system
    modes on the inboard a-set), scaled from mm-kg-s to SI: displacement rows x 1e-3 (m per mm),
    rotations x 1, and one SI modal coordinate = 1/sqrt(1e-6) mm-kg-s ones (energy factor m l^2)."""
    inboard, _ = parts
    asm, sysm = system
    rec = component_recovery(asm, sysm, "inboard", ["grid_disp"])[0]
    assert rec.name == "inboard_grid_disp" and set(rec.units) == {"m", "rad"} and rec.labels[:2] == ("g3:T1", "g3:T2")
    mug1 = op4.read(str(DATA / "inboard.op4"), ["mug1"])["mug1"]
    r = np.array([1e-3 if u == "m" else 1.0 for u in inboard.recovery_item("grid_disp").units])
    ref = r[:, None] * (mug1 @ nas2cam["ulvs"][102]) / math.sqrt(1e-6)
    Y = rec.disp
    f = sysm.freq_hz
    # eigenvectors of distinct modes agree up to sign; those of a close pair (7.0242/7.0254 Hz,
    # gap 1.7e-4) or of the rigid modes only as a subspace: compare projectors Y Y^T.
    groups, j = [], 6
    while j < 54:
        k = j + 1
        while k < 54 and f[k] / f[k - 1] - 1 < 1e-3:
            k += 1
        groups.append(slice(j, k))
        j = k
    groups.append(slice(0, 6))
    worst = 0.0
    for g in groups:
        a, b = Y[:, g] @ Y[:, g].T, ref[:, g] @ ref[:, g].T
        worst = max(worst, np.abs(a - b).max() / np.abs(b).max())
    # Nastran's eigenvectors carry its solver's error (eps |K| / (gap lambda) and more): measured
    # worst 6.3e-9 (the 1.70 Hz mode), the close pair as a subspace 5.6e-10, the rigid subspace 1.5e-10
    assert worst < 1e-7
    assert len(groups) == 48


def test_recovery_rows_are_boundary_motion(parts, system):
    """MUG1 rows of boundary grids reproduce the boundary DOFs: grid 3 (basic output frame)
    directly, grid 11 (output frame CORD2R 10) as T^T times its basic-frame DOFs."""
    asm, sysm = system
    Y = component_recovery(asm, sysm, "inboard", ["grid_disp"])[0].disp
    labels = parts[0].recovery_item("grid_disp").labels
    six = lambda p: [f"{p}:{c}" for c in ("Tx", "Ty", "Tz", "Rx", "Ry", "Rz")]       # noqa: E731
    D3, D11 = displacement_recovery(sysm, six("g3")), displacement_recovery(sysm, six("g11"))
    rows = lambda p: [labels.index(f"{p}:{c}") for c in ("T1", "T2", "T3", "R1", "R2", "R3")]   # noqa: E731
    T = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])    # CORD2R 10: x -> basic y, z -> basic x
    R = np.kron(np.eye(2), T.T)
    # the same rows of the system modes (a product over the boundary DOFs and modes), rotated by
    # an exact permutation: n eps of the rows' scale, n the inner dimension of the recovery
    scale = np.abs(D3).max()
    tol = sum_rtol(sysm.phi.shape[0]) * scale
    assert np.abs(Y[rows("g3")] - D3).max() < tol
    assert np.abs(Y[rows("g11")] - R @ D11).max() < tol


def test_element_force_rows_and_units(parts):
    item = parts[0].recovery_item("bar_forces")
    assert item.labels[:2] == ("e10:1", "e10:2") and len(item.labels) == 16 and set(item.units) == {"N"}
    mef1 = op4.read(str(DATA / "inboard.op4"), ["mef1"])["mef1"]
    # force rows: mN -> N (x 1e-3); columns: a translation boundary DOF of grid 3 (mm -> m: / 1e-3)
    nq = parts[0].n_modes
    col = parts[0].boundary_labels.index("g3:Tz")
    assert np.allclose(item.disp[:, nq + col], 1e-3 * mef1[:, 2] / 1e-3, rtol=1e-13, atol=0)   # two scalings: 2 eps


# -------------------------------------------------------------------- one component
def pyyeti_check(stem: str):
    mats = op4.read(str(DATA / f"{stem}.op4"), ["kxx", "mxx"])
    uset, _, b = bulk.asm2uset(str(DATA / f"{stem}.asm"))
    bset = np.flatnonzero(b)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return pcb.cbcheck(io.StringIO(), mats["mxx"], mats["kxx"], bset, bset[:6], uset,
                           uref=[0.0, 0.0, 0.0], conv=(1e-3, 1.0), n_freefree_modes=12)


@pytest.mark.parametrize("stem", ["inboard", "outboard"])
def test_cb_check_matches_pyyeti_cbcheck(parts, stem):
    cb = parts[0] if stem == "inboard" else parts[1]
    s = cb_check(cb, ref_point=[0.0, 0.0, 0.0]).summary
    ref = pyyeti_check(stem)
    nb = cb.n_boundary
    # same arithmetic on the same numbers (different DOF order and frames): round-off
    assert np.allclose(s["fixed_interface_freq_hz"], ref.cb_frq, rtol=1e-12, atol=0)
    assert np.allclose(s["effective_mass_percent"], ref.effmass_percent.values, rtol=1e-10, atol=1e-10)
    assert np.allclose(s["effective_mass"], ref.effmass.values, rtol=1e-10, atol=1e-14)
    m6 = ref.rbg.T @ ref.m[:nb, :nb] @ ref.rbg           # pyyeti: output frames, converted by cbconvert
    # RB^T M RB: sums over the nb boundary DOFs (with lever arms up to the model's size)
    tol = sum_rtol(nb) * max(1.0, np.abs(cb.point_coords).max()) ** 2
    assert np.allclose(s["rigid_body_mass"], m6, rtol=0, atol=tol * np.abs(m6).max())
    mcg = pcb.cgmass(m6)[1]
    # the c.g.: first moments over the mass, a 3 x 3 solve (eps cond of the mass block)
    assert np.allclose(s["mass_properties_cb"]["cg"], mcg, rtol=0, atol=tol * np.abs(cb.point_coords).max())
    # free-free: liftoff's dense eigensolve with the massless subspace condensed (the inboard
    # M has one massless direction) vs QZ of pyyeti's converted matrices (infinite eigenvalues
    # dropped); measured 1.6e-12 (inboard), 1.4e-10 (outboard)
    assert np.allclose(s["freefree_freq_hz_cb"][6:], np.sqrt(ref_ff(ref)[6:12]) / (2 * np.pi), rtol=1e-8)
    # K RB over the boundary: a product of n = nb terms that cancel (rigid motion): n eps
    assert s["rb_ok"] and max(s["rb_residual"]) < sum_rtol(nb)


def test_system_modes_of_a_component_with_a_massless_direction(parts):
    """The inboard CB mass matrix is singular (one massless direction, eigenvalue -9e-18 of
    15): system_modes condenses it; its 31 finite modes match QZ of the same pencil."""
    cb = parts[0]
    sysm = system_modes(assemble([cb], "inboard_alone"))
    import scipy.linalg as sla

    w = sla.eigvals(cb.K, cb.M)
    w = np.sort(np.abs(np.real(w[np.isfinite(w)])))
    assert sysm.n_modes == 31 == w.size
    # QZ and the condensation agree to 4.5e-11 (1.0e-10 on another machine's BLAS, the
    # second-highest mode) except the highest mode, which lives on the smallest non-zero mass
    # eigenvalue (3.5e-10 of the largest: lambda known to eps/3.5e-10 = 6e-7 by either
    # method); measured 8.5e-9. The others are asked to 1e-8, within that bound.
    assert np.allclose(sysm.omega[6:-1] ** 2, w[6:-1], rtol=1e-8)
    assert sysm.omega[-1] ** 2 == pytest.approx(w[-1], rel=1e-6)
    G = sysm.phi.T @ sysm.assembly.M @ sysm.phi - np.eye(31)
    assert np.abs(G[:30, :30]).max() < 1e-9 and np.abs(G).max() < 1e-7        # measured 6e-11, 9e-9 (last)


def ref_ff(ref) -> np.ndarray:
    import scipy.linalg as sla

    # pyyeti returns no eigenvalues; the free-free problem of its converted matrices by QZ
    w = sla.eigvals(ref.k, ref.m)
    w = np.sort(np.real(w[np.isfinite(w)]))
    return np.abs(w)


def test_mass_matches_nastran_weight_check(parts):
    """Nastran's A-set weight check of the inboard component (inboard.out): mass 1.755052,
    first moments about the basic origin M[1,5] = 1.825251e3 (kg mm)."""
    mp = cb_check(parts[0], ref_point=[0.0, 0.0, 0.0]).summary["mass_properties_cb"]
    assert mp["mass"] == pytest.approx(1.755052, rel=5e-7)        # 7 printed digits
    assert mp["cg"][0] == pytest.approx(1.825251e3 / 1.755052 * 1e-3, rel=1e-6)


def test_nas2cam_gives_the_same_model(parts):
    for se, cb in ((102, parts[0]), (101, parts[1])):
        other = from_nas2cam(DATA / "nas2cam.op2", se=se, name=cb.name, units=MM)
        assert other.boundary_labels == cb.boundary_labels and other.points == cb.points
        assert np.array_equal(other.M, cb.M) and np.array_equal(other.K, cb.K)   # the same numbers


def test_frames_labels_and_order(parts):
    inboard = parts[0]
    assert inboard.n_modes == 8 and inboard.n_boundary == 24
    assert inboard.points == ("g3", "g11", "g19", "g27")
    assert np.allclose(inboard.point_coord("g11"), [0.6, 0.3, 0.3])
    assert inboard.source_units.startswith("mm-kg-s (length 0.001 m")
    raw = op4.read(str(DATA / "inboard.op4"), ["kxx", "mxx"])
    # modes first: Nastran's q-set (rows 24..31) are liftoff's rows 0..7; K_qq = omega^2 unchanged
    assert np.array_equal(np.diag(inboard.K)[:8], np.diag(raw["kxx"])[24:])
    assert np.allclose(inboard.fixed_freq_hz[:3], [6.129345, 6.130134, 23.63188], rtol=1e-6)   # inboard.out
    # grid 11 rotated from CORD2R 10 (frame x = basic y, y = basic z, z = basic x) to basic:
    # its basic Tx is Nastran's T3 (row 8); a translation's mass needs no unit factor (kg)
    i = 8 + inboard.boundary_labels.index("g11:Tx")
    assert inboard.M[i, i] == pytest.approx(raw["mxx"][8, 8], rel=1e-14)        # g11 T3 (mm-kg: kg); copied
    cb = extseout("inboard", grid_names={3: "hd_1", "11": "hd_2"},          # TOML tables have string keys
                  recovery=[NastranRecovery("d", disp="mug1")])
    assert cb.points == ("hd_1", "hd_2", "g19", "g27") and cb.boundary_labels[6] == "hd_2:Tx"
    assert cb.recovery[0].labels[0] == "hd_1:T1" and cb.recovery[0].labels[12] == "hd_2:T1"


def test_cylindrical_output_frame(parts, tmp_path):
    """Grid 19 moved into a cylindrical output frame (CORD2C 20, axis = basic z): the matrices
    are rotated with the closed-form (e_r, e_theta, e_z) at the grid and written by pyyeti's
    wtextseout; the import rotates them back."""
    mats = op4.read(str(DATA / "inboard.op4"), ["kxx", "mxx"])
    uset, _, b = bulk.asm2uset(str(DATA / "inboard.asm"))
    th = math.atan2(300.0, 600.0)                           # grid 19 at (600, 300, 0) mm
    T = np.array([[math.cos(th), -math.sin(th), 0], [math.sin(th), math.cos(th), 0], [0, 0, 1.0]])
    Q = np.eye(32)
    Q[12:15, 12:15] = Q[15:18, 15:18] = T                  # x_basic = Q x_new (grid 19 rows 12..17)
    cyl = np.array([[20, 2, 0], [0.0, 0, 0], [0, 0, 1.0], [1.0, 0, 0]])
    rect10 = np.array([[10, 1, 0], [0.0, 0, 0], [1.0, 0, 0], [0, 1.0, 0]])
    xyz = uset.loc[(slice(None), 1), ["x", "y", "z"]].to_numpy()
    u2 = n2p.addgrid(None, [3, 11, 19, 27], "b", 0, xyz, [0, rect10, cyl, 0])
    name = str(tmp_path / "cyl")
    bulk.wtextseout(name, se=102, bset=np.arange(24), uset=u2, spoint1=2995001, namelist=["kxx", "mxx"],
                    kxx=Q.T @ mats["kxx"] @ Q, mxx=Q.T @ mats["mxx"] @ Q)
    cb = from_extseout(name + ".op4", name="inboard", units=MM)
    ref = parts[0]
    assert cb.boundary_labels == ref.boundary_labels
    # Q^T M Q written and read back with the frames undone: products of n = 3 (rotations), i.e.
    # a few eps of the largest entry; 1e-12 is 4500 eps
    assert np.allclose(cb.M, ref.M, rtol=0, atol=1e-12 * np.abs(ref.M).max())
    assert np.allclose(cb.K, ref.K, rtol=0, atol=1e-12 * np.abs(ref.K).max())


def test_q_set_not_in_cb_form_and_unused_spoints(parts, tmp_path):
    """Modal coordinates in a non-normalised, coupled basis (q = W q', W random) plus two
    unused SPOINTs (zero rows, as when EXTSEOUT reserves more SPOINTs than modes), written
    by pyyeti's wtextseout: the import re-orthonormalises the q-set (eigh of K_qq, M_qq) and
    drops the unused ones. The CB invariants match the original: fixed-interface
    frequencies, M_B, K_B and C_M^T C_M = M_bq M_qq^-1 M_qb."""
    mats = op4.read(str(DATA / "inboard.op4"), ["kxx", "mxx"])
    uset, _, b = bulk.asm2uset(str(DATA / "inboard.asm"))
    S = np.zeros((32, 34))                       # x_old = S x_new; columns 32, 33 unused SPOINTs
    S[:24, :24] = np.eye(24)
    S[24:, 24:32] = np.random.default_rng(7).normal(size=(8, 8)) + 3 * np.eye(8)
    name = str(tmp_path / "skewed")
    bulk.wtextseout(name, se=102, bset=np.arange(24), uset=uset[b], spoint1=2995001, namelist=["kxx", "mxx"],
                    kxx=S.T @ mats["kxx"] @ S, mxx=S.T @ mats["mxx"] @ S)
    cb, ref = from_extseout(name + ".op4", name="inboard", units=MM), parts[0]
    assert cb.n_modes == 8 and cb.boundary_labels == ref.boundary_labels
    assert np.allclose(cb.fixed_omega, ref.fixed_omega, rtol=1e-9)        # eigh of the 8 x 8 pencil
    assert np.allclose(cb.M[:8, :8], np.eye(8), atol=sum_rtol(cb.M.shape[0]))   # M-normalised: n eps
    assert np.abs(cb.K[:8, :8] - np.diag(cb.fixed_omega**2)).max() < 1e-9 * ref.fixed_omega.max() ** 2
    for A, B in ((cb.M_B, ref.M_B), (cb.K_B, ref.K_B), (cb.C_M.T @ cb.C_M, ref.C_M.T @ ref.C_M)):
        assert np.allclose(A, B, rtol=0, atol=1e-10 * np.abs(B).max())
    bad = S.T @ mats["kxx"] @ S
    bad[30, 3] = bad[3, 30] = 1e-3 * np.sqrt(bad[30, 30] * bad[3, 3])       # a modal-boundary stiffness
    bulk.wtextseout(name, se=102, bset=np.arange(24), uset=uset[b], spoint1=2995001, namelist=["kxx", "mxx"],
                    kxx=bad, mxx=S.T @ mats["mxx"] @ S)
    with pytest.raises(InputError, match=r"not a Craig-Bampton model: the modal-boundary stiffness K_qb is "
                                         r"not zero \(relative 1.0e-03\)"):
        from_extseout(name + ".op4", name="inboard", units=MM)


# ------------------------------------------------------------------------------- units
def write_in_units(tmp_path: Path, stem: str, length: float, mass: float) -> Path:
    """The component rewritten by pyyeti in other units: cbconvert / uset_convert with
    (length, mass) conversion factors from mm-kg-s, then wtextseout."""
    mats = op4.read(str(DATA / f"{stem}.op4"), ["kxx", "mxx"])
    uset, _, b = bulk.asm2uset(str(DATA / f"{stem}.asm"))
    bset = np.flatnonzero(b)
    conv = (length, mass)
    u2 = pcb.uset_convert(uset[b], conv=conv)[0]
    name = str(tmp_path / f"{stem}_{length:.6g}")
    bulk.wtextseout(name, se=102, bset=bset, uset=u2, spoint1=int(uset.index[len(bset)][0]),
                    namelist=["kxx", "mxx"], kxx=pcb.cbconvert(mats["kxx"], bset, conv),
                    mxx=pcb.cbconvert(mats["mxx"], bset, conv))
    return Path(name + ".op4")


def test_units_in_lbf_s_and_si_give_the_same_model(parts, tmp_path):
    ref = parts[0]
    inch = from_extseout(write_in_units(tmp_path, "inboard", 1 / 25.4, 1 / SLINCH), name="inboard", units="in-lbf-s")
    si = from_extseout(write_in_units(tmp_path, "inboard", 1e-3, 1.0), name="inboard", units="SI")
    declared = from_extseout(write_in_units(tmp_path, "inboard", 1 / 25.4, 1 / SLINCH), name="inboard",
                             units={"length": 0.0254, "force": LBF, "time": 1.0})
    s_ref = cb_check(ref).summary
    for cb in (inch, si, declared):
        # scaling by factors and back: a few ulps per entry
        assert np.allclose(cb.M, ref.M, rtol=1e-13, atol=1e-13 * np.abs(ref.M).max())
        assert np.allclose(cb.K, ref.K, rtol=1e-13, atol=1e-13 * np.abs(ref.K).max())
        assert np.allclose(cb.fixed_omega, ref.fixed_omega, rtol=1e-13)
        s = cb_check(cb).summary
        # the mass sums a few-ulp-different matrices over its n DOFs: n eps; the free-free
        # frequencies are eigenvalues of them (n eps ||K|| / lambda: 1e-10 for these 32 DOFs)
        assert s["mass_properties_cb"]["mass"] == pytest.approx(s_ref["mass_properties_cb"]["mass"],
                                                                 rel=sum_rtol(cb.M.shape[0]))
        assert np.allclose(s["freefree_freq_hz_cb"][6:], s_ref["freefree_freq_hz_cb"][6:], rtol=1e-10)
        # wtextseout writes GRID coordinates with 8 decimals: 1e-8 in = 2.5e-10 m
        assert np.allclose(cb.point_coords, ref.point_coords, rtol=0, atol=3e-10)
    assert inch.source_units.startswith("in-lbf-s") and si.source_units.startswith("SI")
    assert declared.source_units.startswith("declared (length 0.0254 m, mass 175.1268352")


def test_unit_systems():
    # lbf s^2/in from the definitions (lbm 0.45359237 kg, g_n 9.80665 m/s^2, in 0.0254 m);
    # pyyeti's 'e2m' constant 175.12683524637913 is 5.6e-13 lower
    assert unit_system("in-lbf-s").mass == pytest.approx(0.45359237 * 9.80665 / 0.0254, rel=1e-15)   # same 2 ops
    assert unit_system("in-lbf-s").mass == pytest.approx(175.12683524637913, rel=1e-12)   # pyyeti's 5.6e-13 off
    assert unit_system("mm-t-s").force == pytest.approx(1.0) and unit_system("si").length == 1.0
    assert unit_system({"length": 1e-3, "mass": 1e3, "time": 1.0}).force == pytest.approx(1.0)
    with pytest.raises(InputError, match=r"inconsistent factors"):
        unit_system({"length": 0.0254, "mass": 0.45359237, "time": 1.0, "force": LBF})    # lbm is not consistent
    with pytest.raises(InputError, match=r"units: unknown unit system 'furlong-firkin-fortnight'"):
        unit_system("furlong-firkin-fortnight")


# ------------------------------------------------------------------------------- DMIG
def test_dmig_punch_of_nastran_matrices(parts, tmp_path):
    """Nastran's KXX/MXX written as DMIG punch cards (pyyeti wtdmig: matrix_factory.pch style,
    DMIG* large field, 10 significant digits) with the .asm GRID cards: the same CB model as
    from the OP4, to the punch's 5e-10 relative rounding of each entry."""
    import pandas as pd

    mats = op4.read(str(DATA / "inboard.op4"), ["kxx", "mxx"])
    iddof = bulk.rdextrn(str(DATA / "inboard.pch"))
    idx = pd.MultiIndex.from_arrays([iddof[:, 0], iddof[:, 1]], names=["id", "dof"])
    pch = tmp_path / "inboard_dmig.pch"
    with open(pch, "w") as f:
        bulk.wtdmig(f, {"KAAX": pd.DataFrame(mats["kxx"], idx, idx), "MAAX": pd.DataFrame(mats["mxx"], idx, idx)})
    cb = from_dmig(pch, bulk=DATA / "inboard.asm", name="inboard", units=MM)
    ref = parts[0]
    assert cb.boundary_labels == ref.boundary_labels
    for A, B in ((cb.M, ref.M), (cb.K, ref.K)):
        assert np.all(np.abs(A - B) <= 6e-10 * np.abs(B) + 1e-15 * np.abs(B).max())


@pytest.mark.parametrize("units", ["SI", "in-lbf-s", "mm-t-s"])
def test_dmig_round_trip(parts, tmp_path, units):
    """liftoff -> DMIG punch (in the given units) -> liftoff: the same SI matrices to the
    punch's 10 significant digits (5e-10 relative per entry, 1e-9 with the unit factors)."""
    ref = parts[0]
    path = write_dmig(ref, tmp_path / "inboard.pch", units=units)
    text = path.read_text()
    assert "DMIG*   KAAX" in text and "D+0" in text and "GRID*" in text
    cb = import_nastran(path, name="inboard", units=units)
    assert cb.boundary_labels == ref.boundary_labels and cb.points == ref.points
    for A, B in ((cb.M, ref.M), (cb.K, ref.K)):
        assert np.all(np.abs(A - B) <= 1e-9 * np.abs(B) + 1e-15 * np.abs(B).max())
    assert np.allclose(cb.point_coords, ref.point_coords, rtol=1e-9, atol=1e-12)   # printed with 16 digits (GRID*): 1e-9 relative


# ------------------------------------------------------------------------- file record
def test_save_load_keeps_recovery_and_source_units(parts, tmp_path):
    cb = parts[0]
    back = load_cb(cb.save(tmp_path / "inboard.npz"))
    assert back.source_units == cb.source_units and [r.name for r in back.recovery] == ["grid_disp", "bar_forces"]
    for a, b in zip(back.recovery, cb.recovery):
        assert a.labels == b.labels and a.units == b.units and np.array_equal(a.disp, b.disp) and a.acc is None
    assert np.array_equal(back.M, cb.M)


def test_version_1_files_still_load(parts, tmp_path):
    from liftoff.core.records import write_record

    cb = parts[1]
    data = {"boundary_labels": np.array(cb.boundary_labels), "fixed_omega": cb.fixed_omega, "M": cb.M, "K": cb.K,
            "points": np.array(cb.points), "point_coords": cb.point_coords, "dof_labels": np.array(cb.dof_labels),
            "label_transform": cb.label_transform, "n_dof": np.array(cb.n_dof)}
    path = write_record(tmp_path / "old.npz", "liftoff-cb-model", 1, data, units="SI", attrs={"name": "old"})
    old = load_cb(path)
    assert old.source_units == "SI" and old.recovery == () and np.array_equal(old.K, cb.K)


# --------------------------------------------------------------------------- bad input
def copy_component(tmp_path: Path, stem: str = "inboard") -> Path:
    for ext in (".op4", ".asm", ".pch"):
        shutil.copy(DATA / f"{stem}{ext}", tmp_path / f"{stem}{ext}")
    return tmp_path / f"{stem}.op4"


def one_line(exc) -> str:
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_truncated_op4(tmp_path):
    path = copy_component(tmp_path)
    raw = path.read_bytes()
    path.write_bytes(raw[: len(raw) // 3])                  # binary, cut inside MXX
    with pytest.raises(InputError) as exc:
        from_extseout(path, name="inboard", units=MM)
    assert re.match(rf"{re.escape(str(path))}: (OP4|mxx|matrix 'mxx')", one_line(exc))
    mats = op4.read(str(DATA / "inboard.op4"))
    op4.write(str(path), mats, binary=False)                # ASCII, cut half-way
    text = path.read_text()
    path.write_text(text[: len(text) // 2])
    with pytest.raises(InputError) as exc:
        from_extseout(path, name="inboard", units=MM)
    assert one_line(exc).startswith(f"{path}: ")


def test_ascii_op4_reads_like_binary(parts, tmp_path):
    path = copy_component(tmp_path)
    op4.write(str(path), op4.read(str(DATA / "inboard.op4")), binary=False)
    assert path.read_bytes()[:40].strip().startswith(b"32")          # text header
    cb = from_extseout(path, name="inboard", units=MM)
    # ASCII OP4 holds 17 significant digits (1P,3E23.16): exact round trip of doubles
    assert np.array_equal(cb.M, parts[0].M) and np.array_equal(cb.K, parts[0].K)


def test_wrong_matrix_size(tmp_path):
    path = copy_component(tmp_path)
    mats = op4.read(str(DATA / "inboard.op4"))
    mats["kxx"] = mats["kxx"][:30, :30]
    op4.write(str(path), mats)
    with pytest.raises(InputError) as exc:
        from_extseout(path, name="inboard", units=MM)
    assert one_line(exc) == f"{path}: kxx: matrix is 30 x 30, but {tmp_path / 'inboard.pch'} lists 32 a-set DOFs"


def test_boundary_grid_missing_from_asm(tmp_path):
    path = copy_component(tmp_path)
    asm = tmp_path / "inboard.asm"
    lines = asm.read_text().splitlines(keepends=True)
    k = next(i for i, s in enumerate(lines) if s.startswith("GRID*") and s.split()[1] == "19")
    asm.write_text("".join(lines[:k] + lines[k + 2:]))
    with pytest.raises(InputError) as exc:
        from_extseout(path, name="inboard", units=MM)
    assert one_line(exc) == f"{asm}: boundary grid 19 has no GRID card (or an incomplete one)"


def test_unknown_unit_system_and_other_errors(tmp_path):
    with pytest.raises(InputError) as exc:
        extseout("inboard", units="furlongs")
    assert re.match(r"Nastran component 'inboard' \(.*inboard\.op4.*\): units: unknown unit system 'furlongs'",
                    one_line(exc))
    with pytest.raises(InputError, match=r"inboard\.op4: matrix 'kaa' not found \(the file has kxx, mxx"):
        extseout("inboard", stiffness="KAA")
    with pytest.raises(InputError, match=r"nope\.op4: EXTSEOUT OP4 file not found"):
        from_extseout(tmp_path / "nope.op4", name="x", units=MM)
    with pytest.raises(InputError, match=r"grids 3 and 11 are both named 'a'"):
        extseout("inboard", grid_names={3: "a", 11: "a"})
    with pytest.raises(InputError, match=r"'se' is not an option of from_extseout"):
        import_nastran(DATA / "inboard.op4", name="x", units=MM, se=3)
    with pytest.raises(InputError, match=r"superelement 7: no USET"):
        from_nas2cam(DATA / "nas2cam.op2", se=7, name="x", units=MM)
    with pytest.raises(InputError, match=r"recovery 'r': 5 row labels for 36 matrix rows"):
        extseout("inboard", recovery=[NastranRecovery("r", disp="mug1", rows=[f"y{k}" for k in range(5)],
                                                      quantity="length")])
    with pytest.raises(InputError, match=r"recovery 'r': quantity 'displacement' needs rows named by DOF"):
        extseout("inboard", recovery=[NastranRecovery("r", disp="mef1")])


def test_boundary_grid_with_one_component():
    """EXTRN `475 2`: grid 475 (basic output frame) is a boundary point with Ty only. The
    import keeps the 19 boundary DOFs in EXTRN order, and the geometric rigid-body check
    K_B RB = 0 holds. The matrices are Nastran's, moved to modes first and scaled by the
    in-lbf-s factors alone (all frames basic)."""
    cb = from_extseout(DATA / "reduced_bset_notall6.op4", name="se75", units="in-lbf-s")
    assert cb.n_modes == 10 and cb.n_boundary == 19 and cb.boundary_labels[-1] == "g475:Ty"
    s = cb_check(cb).summary
    assert s["rb_ok"] and max(s["rb_residual"]) < 1e-10            # measured 1.2e-12
    raw = op4.read(str(DATA / "reduced_bset_notall6.op4"), ["kaa", "maa"])
    order = np.r_[np.arange(19, 29), np.arange(19)]
    f = unit_system("in-lbf-s")
    assert np.allclose(cb.K[:10, :10], raw["kaa"][np.ix_(order, order)][:10, :10], rtol=1e-14)    # omega^2
    # a translation-translation mass entry scales by the mass factor only
    assert cb.M[-1, -1] == pytest.approx(raw["maa"][18, 18] * f.mass, rel=1e-14)   # one product: 1 eps


def test_matrix_names_that_cannot_be_right():
    """Issue 27: a mass name absent from the file, or the stiffness's own, is one line."""
    from liftoff.core.errors import InputError

    with pytest.raises(InputError, match="matrix 'kaax' not found"):
        extseout("inboard", mass="KAAX")
    with pytest.raises(InputError, match="stiffness and mass both name the matrix 'kxx'"):
        extseout("inboard", mass="kxx")


def test_op4_round_trip(tmp_path):
    """write_op4 then pyyeti's reader and read_op4: the matrices back bit for bit (binary,
    double precision); bad names and non-finite matrices refused in one line."""
    pytest.importorskip("pyyeti")
    from pyyeti.nastran import op4

    from liftoff.reduction import read_op4, write_op4

    rng = np.random.default_rng(7)
    mats = {"FREQ": rng.uniform(0, 50, (9, 1)), "R0001A": rng.standard_normal((6, 9)), "KAA": np.eye(3)}
    path = write_op4(tmp_path / "x.op4", mats)
    theirs = op4.read(str(path))
    ours = read_op4(path)
    for name, m in mats.items():
        assert np.array_equal(np.asarray(theirs[name.lower()]), m) and np.array_equal(ours[name.lower()], m)
    with pytest.raises(InputError, match="upper case"):
        write_op4(tmp_path / "y.op4", {"toolongname": np.eye(2)})
    with pytest.raises(InputError, match="finite"):
        write_op4(tmp_path / "y.op4", {"BAD": np.array([[np.nan]])})
    assert not (tmp_path / "y.op4").exists()


def test_an_unsymmetric_stiffness_is_refused(tmp_path):
    """A corrupt or unsymmetric OP4 (one K entry changed in one triangle, 1.6e-4 of K's largest)
    was accepted: the eigensolvers read one triangle, and the system frequencies moved by up to
    4.2 % between K and K^T (a review, 2026-12-07). Refused by validate_cb (SYMMETRY_TOL 1e-8:
    the real file's K and M are symmetric to round-off), naming the matrix and the entry."""
    from liftoff.reduction.nastran import read_op4, write_op4

    for ext in (".asm", ".pch"):
        shutil.copy(DATA / f"outboard{ext}", tmp_path / f"outboard{ext}")
    mats = read_op4(DATA / "outboard.op4")
    K = mats["kxx"]
    assert np.abs(K - K.T).max() <= 1e-12 * np.abs(K).max()
    K = K.copy()
    K[30, 31] += 0.3 * abs(K[31, 31])
    write_op4(tmp_path / "outboard.op4", {k.upper(): (K if k == "kxx" else v) for k, v in mats.items()})
    with pytest.raises(InputError, match=r"K is not symmetric: \|K - K\^T\| reaches .* of its largest entry") as exc:
        from_extseout(tmp_path / "outboard.op4", name="ob", units=MM)
    assert "\n" not in str(exc.value)
