"""Fixtures for the command-line tests: a small valid scenario that each test breaks one way.

The bodies are closed-form lumped models (not the code under test):
vehicle = two masses m1 (``base``) and m2 (``top``) joined by an axial spring k, free-free,
with a rigid lateral (x) mode; pad = a block of mass mp on springs kx, kz to ground.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from liftoff.transient import ModalBody, save_body

M1, M2, K_AXIAL = 10.0, 30.0, 4.0e6          # kg, kg, N/m
MP, KPX, KPZ = 50.0, 2.0e7, 5.0e7            # kg, N/m, N/m


def vehicle_body() -> ModalBody:
    mt = M1 + M2
    c = 1.0 / math.sqrt(M1 * M2**2 + M2 * M1**2)
    w = math.sqrt(K_AXIAL * mt / (M1 * M2))
    # columns: rigid x, rigid z, elastic z ; rows base:Tx base:Tz top:Tx top:Tz
    phi = np.array([[1 / math.sqrt(mt), 0, 0],
                    [0, 1 / math.sqrt(mt), c * M2],
                    [1 / math.sqrt(mt), 0, 0],
                    [0, 1 / math.sqrt(mt), -c * M1]])
    part = np.zeros((3, 6))
    part[0, 0] = part[1, 2] = math.sqrt(mt)   # Phi^T M RB: translations only (point masses on the axis)
    rbm = np.diag([mt, mt, mt, 1.0, 1.0, 1.0])
    return ModalBody("vehicle", omega=[0.0, 0.0, w], zeta=[0.0, 0.0, 0.01],
                     dof_labels=("base:Tx", "base:Tz", "top:Tx", "top:Tz"), phi=phi,
                     participation=part, rigid_body_mass=rbm)


def pad_body() -> ModalBody:
    phi = np.eye(2) / math.sqrt(MP)
    part = np.zeros((2, 6))
    part[0, 0] = part[1, 2] = math.sqrt(MP)
    return ModalBody("pad", omega=[math.sqrt(KPX / MP), math.sqrt(KPZ / MP)], zeta=[0.02, 0.02],
                     dof_labels=("post:Tx", "post:Tz"), phi=phi, participation=part,
                     rigid_body_mass=np.diag([MP, MP, MP, 1.0, 1.0, 1.0]))


def base_scenario() -> dict:
    return {
        "title": "cli fixture",
        "bodies": {"a": "vehicle.npz", "b": "pad.npz"},
        "time": {"t_end": 0.02, "h": 1.0e-4},
        "gravity": {"accel": [0.0, 0.0, -9.81]},
        "contact": [{"name": "post", "labels_a": ["base:Tx", "base:Tz"],
                     "labels_b": ["post:Tx", "post:Tz"], "stiffness": [1.0e8, 1.0e8],
                     "axial": 1, "release_time": 0.005}],
        "force": [{"body": "a", "label": "top:Tz", "csv": "thrust.csv"},
                  {"body": "a", "label": "top:Tx", "value": 10.0}],
        "initial": {"mode": "static"},
        "output": {"a": ["top:Tz", "base:Tz"], "b": ["post:Tz"]},
    }


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
    if isinstance(v, int):
        return str(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    raise TypeError(type(v))


def dump_toml(data: dict) -> str:
    """Minimal TOML writer for the scenario dicts of these tests (tables one level deep)."""
    lines = [f"{k} = {_value(v)}" for k, v in data.items() if not isinstance(v, (dict, list))
             or (isinstance(v, list) and not (v and isinstance(v[0], dict)))]
    for k, v in data.items():
        if isinstance(v, dict):
            lines += ["", f"[{k}]"] + [f"{kk} = {_value(vv)}" for kk, vv in v.items()]
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                lines += ["", f"[[{k}]]"] + [f"{kk} = {_value(vv)}" for kk, vv in item.items()]
    return "\n".join(lines) + "\n"


@pytest.fixture
def case_dir(tmp_path: Path) -> Path:
    """A directory with vehicle.npz, pad.npz and thrust.csv (time s, force N)."""
    save_body(vehicle_body(), tmp_path / "vehicle.npz")
    save_body(pad_body(), tmp_path / "pad.npz")
    (tmp_path / "thrust.csv").write_text("time,force\n0.0,0.0\n0.004,0.0\n0.006,2000.0\n0.02,2000.0\n")
    return tmp_path


def write_scenario(directory: Path, data: dict, name: str = "scenario.toml") -> Path:
    path = directory / name
    path.write_text(dump_toml(data))
    return path
