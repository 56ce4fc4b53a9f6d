"""Regenerate the bodies of the drop example (SI units): rod.npz and block.npz.

Rod: a uniform steel rod, 1 m long, 1e-3 m^2 (7.8 kg), hanging vertically (axis z), its
axial free-free modes in closed form (transient.examples.free_free_rod: rigid + 29 elastic
modes, 1 % damping). Block: a 5 kg block on a 1e6 N/m spring to ground (one mode, 2 %).
The rod starts at rest 50 mm above the block and falls under gravity (scenario.toml).

    .venv/bin/python examples/drop_rod/make_bodies.py [OUT_DIR]   (default: this directory)
"""
import math
import sys
from pathlib import Path

from liftoff.transient import save_body
from liftoff.transient.examples import free_free_rod, spring_block

HERE = Path(__file__).resolve().parent
L, E, RHO, A = 1.0, 200e9, 7800.0, 1e-3          # m, Pa, kg/m^3, m^2
BLOCK_MASS, BLOCK_K = 5.0, 1.0e6                  # kg, N/m


def main(out: Path = HERE) -> None:
    out.mkdir(parents=True, exist_ok=True)
    rod = free_free_rod(L, E, RHO, A, n_modes=30, zeta=0.01, name="rod", end_labels=("rod_bottom", "rod_top"),
                        component="Tz", origin=0.05, stations=3)
    block = spring_block(BLOCK_MASS, BLOCK_K, zeta=0.02, name="block", point="block", component="Tz")
    save_body(rod, out / "rod.npz")
    save_body(block, out / "block.npz")
    sag = -BLOCK_MASS * 9.81 / BLOCK_K
    print(f"wrote rod.npz ({rod.n_modes} modes) and block.npz; block static sag {sag:.6g} m "
          f"-> [initial] q_b = [{sag * math.sqrt(BLOCK_MASS):.6g}]")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
