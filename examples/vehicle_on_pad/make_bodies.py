"""Regenerate the bodies and thrust curve of the lift-off example (SI units).

vehicle.npz: a free-free 50 t "vehicle" (transient.examples.toy_vehicle: a 20 m pin-jointed
truss on 4 base posts, 6 rigid + 21 elastic modes from K, M by scipy eigh, 2 % damping).
pad.npz: a grounded 20 t flexible "pad" (transient.examples.toy_pad: one node under each
post on three bars to anchors, 12 modes, 5 % damping).
thrust.csv: total engine thrust (N) against time (s): ignition ramp to 1.3 x the vehicle
weight while bolted, held; the bolts are released at 0.5 s (scenario.toml).

    .venv/bin/python examples/vehicle_on_pad/make_bodies.py [OUT_DIR]   (default: this directory)
"""
import sys
from pathlib import Path

import numpy as np

from liftoff.transient import save_body
from liftoff.transient.examples import toy_pad, toy_vehicle

HERE = Path(__file__).resolve().parent
N_POSTS, G = 4, 9.81


def main(out: Path = HERE) -> None:
    out.mkdir(parents=True, exist_ok=True)
    vehicle, pad = toy_vehicle(N_POSTS), toy_pad(N_POSTS)
    save_body(vehicle, out / "vehicle.npz")
    save_body(pad, out / "pad.npz")
    weight = vehicle.mass * G
    t = np.array([0.0, 0.1, 0.4, 2.0])
    thrust = np.array([0.0, 0.0, 1.3 * weight, 1.3 * weight])
    with open(out / "thrust.csv", "w") as fh:
        fh.write("time_s,thrust_N\n")
        for ti, fi in zip(t, thrust):
            fh.write(f"{ti:.4f},{fi:.1f}\n")
    print(f"wrote vehicle.npz ({vehicle.n_modes} modes, {vehicle.mass:.0f} kg), pad.npz ({pad.n_modes} modes), "
          f"thrust.csv (peak {thrust.max():.4g} N = 1.3 x weight)")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE)
