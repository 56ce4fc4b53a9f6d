"""Default launch pad: groups, clamped pedestal bases, post-top patches coinciding with the
booster hold-down points, CAD volumes vs closed form, MLP mass."""
from __future__ import annotations

import numpy as np
import pytest

from liftoff.meshes import PadParams
from liftoff.meshes.pad import pad_closed_form_volumes


def test_groups_clamps_and_posts(pad, msh_groups):
    groups = msh_groups(pad)
    names = {n for _, n in groups}
    posts = {f"pad_post_{s}_{k}" for s in ("left", "right") for k in range(1, 5)}
    bases = {f"pad_pedestal_{k}_base" for k in range(1, 7)}
    assert set(groups) == {(3, "pad_deck"), (3, "pad_posts"), (3, "pad_pedestals")} | {
        (2, n) for n in posts | bases}
    assert {p.name for p in pad.patches} == posts and set(pad.clamped) == bases and names
    p = PadParams()
    z_ground = -p.post_height - p.deck_thickness - p.pedestal_height
    for b in bases:
        n = groups[(2, b)]["nodes"]
        assert len(n) >= 4 and np.abs(n[:, 2] - z_ground).max() < 1e-9
        assert groups[(2, b)]["measure"] == pytest.approx(p.pedestal_size ** 2, rel=1e-9)
    for patch in pad.patches:
        n = groups[(2, patch.name)]["nodes"]
        assert len(n) >= 6
        assert np.abs(n[:, 2]).max() < 1e-9  # post tops at the hold-down level z = 0
        assert np.abs(n[:, :2] - patch.ref_point[:2]).max() <= p.post_size / 2 + 1e-9
    assert 2_000 < pad.mesh_nodes < 20_000


def test_posts_coincide_with_booster_holddowns(pad, stack):
    srb = {p.name: p.ref_point for s in ("left", "right") for p in stack[f"srb_{s}"].patches}
    for p in pad.patches:
        side, k = p.name.split("_")[2:]
        np.testing.assert_array_equal(p.ref_point, srb[f"srb_{side}_hd_{k}"])


def test_volumes_and_mass(pad, msh_groups):
    p = PadParams()
    expect = pad_closed_form_volumes(p)
    for name, v in pad.group_volumes.items():
        assert v == pytest.approx(expect[name], rel=1e-9)  # boxes and cylinders: exact in OCC
        # flat faces are meshed exactly; the exhaust-hole cylinders are faceted (< 0.1 %)
        assert msh_groups(pad)[(3, name)]["measure"] == pytest.approx(v, rel=1e-3)
    mlp = sum(pad.volumes[g].rho * pad.group_volumes[g] for g in ("pad_deck", "pad_posts"))
    # rho = mass / volume per group, then rho V summed over two groups: a few roundings (1e-12 = 4500 eps)
    assert mlp == pytest.approx(3_730_000.0, rel=1e-12)  # MLP ~3,730 t (docs/meshes.md)
    deck = pad.volumes["pad_deck"]
    assert deck.E == pytest.approx(6 * 200e9 * p.deck_flange_thickness / p.deck_thickness, rel=1e-12)  # 3 roundings
