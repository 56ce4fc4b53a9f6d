"""Two-body modal contact transient (Prabhakar & Palermo), numpy + numba only."""
from .body import ModalBody, ground, load_body, save_body
from .coefficients import StepCoefficients, step_coefficients
from .errors import ConvergenceError, InputError
from .model import (ContactPoint, Forcing, InitialState, ModalFeedback, ModalForce, PointForce, Recovery,
                    TabulatedForce, TransientProblem)
from .result import TransientResult, load_result
from .solver import estimate_step, solve, static_equilibrium, static_solution

__all__ = ["ModalBody", "ground", "load_body", "save_body", "InputError", "ConvergenceError",
           "StepCoefficients", "step_coefficients", "ContactPoint", "PointForce", "TabulatedForce", "ModalForce",
           "ModalFeedback", "Forcing", "Recovery", "InitialState", "TransientProblem", "TransientResult",
           "load_result", "solve", "static_equilibrium", "static_solution", "estimate_step"]
