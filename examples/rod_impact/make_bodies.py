"""Regenerate the bodies of the rod-impact example (SI units): rod_a.npz and rod_b.npz.

Two equal uniform aluminium rods (1 m, 1e-3 m^2, 2.7 kg), each represented by the
closed-form axial modes of a free-free rod (transient.examples.free_free_rod: rigid +
99 elastic modes, undamped), end to end along x. Rod A moves at 2 m/s towards rod B at
rest. 1-D wave theory: force plateau rho c A v0 / 2 = 13.75 kN for 2 L / c = 0.39 ms,
then the rods part with their velocities exchanged.

    .venv/bin/python examples/rod_impact/make_bodies.py [OUT_DIR]   (default: this directory)
"""
import sys
from pathlib import Path

from liftoff.transient import save_body
from liftoff.transient.examples import free_free_rod

HERE = Path(__file__).resolve().parent
L, E, RHO, A, N_MODES = 1.0, 70e9, 2700.0, 1e-3, 100


def main(out: Path = HERE) -> None:
    out.mkdir(parents=True, exist_ok=True)
    rod_a = free_free_rod(L, E, RHO, A, N_MODES, name="rod_a", end_labels=("a0", "a1"), component="Tx",
                          origin=-L, stations=1)
    rod_b = free_free_rod(L, E, RHO, A, N_MODES, name="rod_b", end_labels=("b0", "b1"), component="Tx",
                          origin=0.0, stations=1)
    save_body(rod_a, out / "rod_a.npz")
    save_body(rod_b, out / "rod_b.npz")
    print(f"wrote rod_a.npz and rod_b.npz ({N_MODES} modes each)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
