"""Two-body modal contact transient (Prabhakar & Palermo), numpy + numba only."""

from liftoff.core.lazy import lazy_exports

_EXPORTS = {
    "ModalBody": ".body",
    "ground": ".body",
    "load_body": ".body",
    "save_body": ".body",
    "StepCoefficients": ".coefficients",
    "step_coefficients": ".coefficients",
    "ConvergenceError": "liftoff.core.errors",
    "InputError": "liftoff.core.errors",
    "ContactPoint": ".model",
    "Forcing": ".model",
    "InitialState": ".model",
    "ModalFeedback": ".model",
    "ModalForce": ".model",
    "PointForce": ".model",
    "Recovery": ".model",
    "TabulatedForce": ".model",
    "TransientProblem": ".model",
    "TransientResult": ".result",
    "load_result": ".result",
    "estimate_step": ".stepping",
    "choose_step": ".stepping",
    "StepChoice": ".stepping",
    "solve_estimated": ".accuracy",
    "Estimated": ".accuracy",
    "peak_errors": ".accuracy",
    "ResourceError": "liftoff.core.errors",
    "solve": ".solver",
    "solve_batch": ".batch",
    "solve_batch_iter": ".batch",
    "static_equilibrium": ".solver",
    "static_solution": ".solver",
}
__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
