"""Two-body modal contact transient (Prabhakar & Palermo), numpy + numba only."""
from .body import ModalBody, ground, load_body, save_body
from .errors import ConvergenceError, InputError

__all__ = ["ModalBody", "ground", "load_body", "save_body", "InputError", "ConvergenceError"]
