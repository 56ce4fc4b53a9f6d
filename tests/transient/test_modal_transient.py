"""A plain modal transient (no contact points), the equivalent of pyyeti's
``SolveUnc.tsolve``: the same exact step for a force linear over each step (pyyeti's
first-order hold, ``order=1``), forcing and output recovery as the contact transient."""
import numpy as np
import pytest

from liftoff.transient import Forcing, ModalForce, TabulatedForce, TransientProblem, ground, solve
from liftoff.transient.examples import toy_pad, toy_vehicle

ode = pytest.importorskip("pyyeti.ode")


@pytest.mark.parametrize("which", ["free-free vehicle", "grounded pad"])
def test_against_pyyeti_solveunc(which):
    """Both integrate q'' + 2 zeta omega q' + omega^2 q = P(t) exactly for P linear between
    samples; they differ only by rounding in the coefficients (pyyeti: matrix exponential;
    here: closed forms/series, 2.4e-14 against lsim): rtol 1e-10 of the peak response."""
    body = toy_vehicle() if which.startswith("free") else toy_pad()
    h, n_t = 2e-4, 2001
    t = h * np.arange(n_t)
    label = body.dof_labels[2]
    ramp = TabulatedForce("a", label, [0.0, 0.05, 0.12, 0.4], [0.0, 3e4, -1e4, 0.0])
    rng = np.random.default_rng(7)
    tm = np.linspace(0.0, t[-1], 41)                       # a modal force table on its own grid
    modal = ModalForce("a", tm, rng.normal(0, 50.0, (tm.size, body.n_modes)))
    problem = TransientProblem(body, ground(), [], Forcing(tables=[ramp], modal=[modal]), t_end=t[-1], h=h,
                               initial="zero", keep_modal=True, outputs={"a": [label]}, progress=False)
    res = solve(problem)
    # the same modal forcing, sampled at the steps (exact: every breakpoint is a step time)
    P = np.outer(body.phi[body.dof_index(label)], np.interp(t, ramp.time, ramp.value))
    P += np.column_stack([np.interp(t, tm, modal.values[:, k]) for k in range(body.n_modes)]).T
    k, c = np.diag(body.omega ** 2), np.diag(2 * body.zeta * body.omega)
    sol = ode.SolveUnc(None, c, k, h, order=1).tsolve(P, d0=np.zeros(body.n_modes), v0=np.zeros(body.n_modes))
    q = res.modal["q_a"]
    print(f"{which}: max |q - pyyeti| / max |q| = {np.abs(q - sol.d.T).max() / np.abs(sol.d).max():.2e}")
    assert res.time.size == n_t and np.allclose(res.time, t, rtol=0, atol=1e-12)
    assert np.abs(q - sol.d.T).max() <= 1e-10 * np.abs(sol.d).max()
    assert np.abs(res.modal["v_a"] - sol.v.T).max() <= 1e-10 * np.abs(sol.v).max()
    assert np.abs(res.modal["acc_a"] - sol.a.T).max() <= 1e-10 * np.abs(sol.a).max()
    y = res.displacement["a"][:, 0]
    assert np.abs(y - body.phi[body.dof_index(label)] @ sol.d).max() <= 1e-10 * np.abs(y).max()
