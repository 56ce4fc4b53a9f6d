"""Regenerate the bodies of the docking example (SI units): chaser.npz and target.npz.

Two free-free flexible "modules" (transient.examples.module_truss: pin-jointed trusses,
6 t each, 6 rigid + 21 elastic modes, 2 % damping), meeting along x at a docking ring of
four latch points (radius 1 m) whose contact normals are inclined 30 degrees by guide
petals (transient.examples.docking_contacts; the contacts are written in scenario.toml).

    .venv/bin/python examples/docking/make_bodies.py [OUT_DIR]   (default: this directory)
"""
import sys
from pathlib import Path

from liftoff.transient import save_body
from liftoff.transient.examples import module_truss, truss_body

HERE = Path(__file__).resolve().parent


def main(out: Path = HERE) -> None:
    out.mkdir(parents=True, exist_ok=True)
    save_body(truss_body(module_truss("a"), "chaser", zeta=0.02), out / "chaser.npz")
    save_body(truss_body(module_truss("b"), "target", zeta=0.02), out / "target.npz")
    print("wrote chaser.npz and target.npz (27 modes each)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
