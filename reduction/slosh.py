"""Slosh pendulums on a component's DOFs (issue 25): what reduction needs of fem.slosh's
SloshPendulums (``[model] convective = "slosh"``), kept with the component and saved in its
file, so that the Craig-Bampton model recovers each pendulum's force and a run can report
the tanks' slosh modes.

Pendulum n is one DOF of the component (``dofs[n]``: the bob's lateral displacement along
``direction[n]``, m) with mass ``mass[n]`` (kg) and a spring ``stiffness[n]`` (N/m) on the
stretch s_n - r_n . x; ``stretch`` holds the rows e_{s_n} - r_n (n x n_dof), so that the
spring force on the bob is -k_n stretch_n . x and the pendulum's force on the tank
F_n = k_n stretch_n . x (N, along ``direction[n]``). ``frequency`` (Hz) is the rigid-tank
slosh frequency at the liquid's g_eff (``gravity``, m/s^2), ``position`` the bob's point (m),
``wave_per_force`` (m/N) the mode's largest free-surface rise per newton of its force (so
that the wave height of mode n is wave_per_force[n] F_n). Units SI.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from liftoff.core.errors import InputError


@dataclass
class SloshDOFs:
    names: tuple
    liquid: tuple
    dofs: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    frequency: np.ndarray
    gravity: np.ndarray
    direction: np.ndarray
    position: np.ndarray
    stretch: sp.csr_matrix
    wave_per_force: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.names, self.liquid = tuple(str(s) for s in self.names), tuple(str(s) for s in self.liquid)
        self.dofs = np.asarray(self.dofs, np.int64).reshape(-1)
        for nm in ("mass", "stiffness", "frequency", "gravity"):
            setattr(self, nm, np.asarray(getattr(self, nm), float).reshape(-1))
        self.direction = np.asarray(self.direction, float).reshape(-1, 2)
        self.position = np.asarray(self.position, float).reshape(-1, 3)
        self.stretch = sp.csr_matrix(self.stretch, dtype=float)
        n = self.dofs.size
        self.wave_per_force = (np.full(n, np.nan) if self.wave_per_force is None
                               else np.asarray(self.wave_per_force, float).reshape(-1))
        sizes = {len(self.names), len(self.liquid), self.mass.size, self.stiffness.size, self.frequency.size,
                 self.gravity.size, self.direction.shape[0], self.position.shape[0], self.stretch.shape[0],
                 self.wave_per_force.size}
        if sizes != {n}:
            raise InputError(f"slosh pendulums: inconsistent sizes {sorted(sizes)} for {n} DOFs")
        if not (np.all(self.mass > 0) and np.all(self.stiffness > 0)):
            raise InputError("slosh pendulums: masses and stiffnesses must be > 0")

    @property
    def n(self) -> int:
        return int(self.dofs.size)

    @property
    def n_dof(self) -> int:
        return int(self.stretch.shape[1])

    def force_rows(self) -> sp.csr_matrix:
        """(n, n_dof): F_n = row_n . x, N, each pendulum's force on the tank along its direction."""
        return sp.diags(self.stiffness) @ self.stretch

    def cb_recovery(self, fim: np.ndarray, cm: np.ndarray, prefix: str = "") -> tuple:
        """``<prefix>slosh_force`` (disp rows, N) and ``<prefix>slosh_wave_height`` (disp rows,
        m: each mode's crest, signed as its force) over a CB model's DOFs [q; x_b]."""
        from .craig_bampton import CBRecovery

        T = np.hstack([fim, cm])
        F = np.asarray(self.force_rows() @ T)
        out = [CBRecovery(f"{prefix}slosh_force", self.names, ("N",) * self.n, disp=F)]
        if np.all(np.isfinite(self.wave_per_force)):
            out.append(CBRecovery(f"{prefix}slosh_wave_height", self.names, ("m",) * self.n,
                                  disp=self.wave_per_force[:, None] * F))
        return tuple(out)

    def record(self) -> dict:
        from .component import _csr_record

        return {"slosh_names": np.array(self.names, dtype="U"), "slosh_liquid": np.array(self.liquid, dtype="U"),
                "slosh_dofs": self.dofs, "slosh_mass": self.mass, "slosh_stiffness": self.stiffness,
                "slosh_frequency": self.frequency, "slosh_gravity": self.gravity, "slosh_direction": self.direction,
                "slosh_position": self.position, "slosh_stretch": _csr_record(self.stretch),
                "slosh_wave_per_force": self.wave_per_force}

    @classmethod
    def from_record(cls, z: dict) -> "SloshDOFs | None":
        from .component import _csr_from

        if "slosh_names" not in z:
            return None
        return cls(tuple(z["slosh_names"]), tuple(z["slosh_liquid"]), z["slosh_dofs"], z["slosh_mass"],
                   z["slosh_stiffness"], z["slosh_frequency"], z["slosh_gravity"], z["slosh_direction"],
                   z["slosh_position"], _csr_from(z["slosh_stretch"]), z.get("slosh_wave_per_force"))
