"""The default core stage with shell walls against the thickened solid (issue 11's checks):
the same total mass, and the first free-free beam-bending frequency within a few percent.
Like for like: the shell carries the solid's rigid 1 m x 1 m attach patches here (the
default's attach rings add no stiffness, so the patches' local stiffening goes: -6.5 % on
this mesh; the pressurised default is benchmarks/bench_prestress.py's).

The shell model is the wall's mid-surface as a bare Al 2219 skin of the thickness that
weighs the dry mass (6.8 mm): membrane stiffness and mass are the thickened solid's, so beam
modes (membrane-dominated) must agree; the skin's bending stiffness is (0.15 m / 6.8 mm)^2
= 490 times lower, so its lobar modes are far lower (87 below 5 Hz) and the first beam mode
sits among them. It is found by a shift-invert solve centred on the solid's beam frequency
and picked by its beam content (the share of the lateral displacement that is a rigid
translation of each cross-section).
"""
import numpy as np
import pytest

from liftoff.fem import build_model, eigenmodes, mass_properties, petsc_backend as pb
from liftoff.fem.modes import beam_content
from liftoff.meshes.vehicle import build_core_stage

pytestmark = [pytest.mark.fem, pytest.mark.slow]     # ~20 s (two core models, a 60-mode solve)


def test_core_stage_shell_walls_against_solid(tmp_path):
    solid = build_model(build_core_stage(tmp_path / "solid"))
    shell = build_model(build_core_stage(tmp_path / "shell", mesh_size=1.8, walls="shell", attach="patch"))
    m_solid, m_shell = mass_properties(solid), mass_properties(shell)
    err = m_shell.mass / m_solid.mass - 1
    print(f"core mass: shell {m_shell.mass:.1f} kg, solid {m_solid.mass:.1f} kg ({err:+.4%}); "
          f"c.g. {m_shell.cg[2]:.3f} / {m_solid.cg[2]:.3f} m")
    # both carry the same dry and propellant masses; the rest is faceting of curved walls
    # (chords: (h/R)^2/24 of the 26.5 t wall, 3.5 % of the total mass)
    assert abs(err) < 1e-3
    # c.g. (measured 13 mm apart): the liquid is smeared over the wetted mid-surface here and
    # over the inner wall there, t/2 = 75 mm apart on the domes, which hold about a third of
    # the wetted area; the tolerance is that offset times that share (25 mm)
    assert abs(m_shell.cg[2] - m_solid.cg[2]) < 0.025
    modes = eigenmodes(solid, n_modes=8)
    f_solid = modes.freq_hz[6]
    assert beam_content(solid, modes.shapes[:, 6]) > 0.9
    lam, Phi = pb.eigensolve(shell.K, shell.M, 60, (2 * np.pi * f_solid) ** 2, what="core shell")
    f = np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)
    share = np.array([beam_content(shell, Phi[:, j]) for j in range(f.size)])
    f_beam = f[(share > 0.5) & (f > 0.5)].min()       # rigid translations are 'beam' too
    print(f"first beam bending: shell {f_beam:.3f} Hz, solid {f_solid:.3f} Hz ({f_beam / f_solid - 1:+.2%}); "
          f"shell modes near it {np.round(f[:12], 3)}")
    # within a few percent: the P1 solid's beam mode is itself 1.6 % above the same mesh with
    # P2 tetrahedra (4.553 Hz), and the shell with the solid's bending stiffness converges to
    # 4.43 Hz (1.8 to 0.9 m meshes); the bare skin's cross-sections ovalise a little more.
    # Measured -5.2 % on this 1.8 m mesh (42k DOFs), -4.8 % on the 0.9 m one (104k DOFs).
    assert abs(f_beam / f_solid - 1) < 0.06
