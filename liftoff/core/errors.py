"""Errors that carry a one-line, user-facing message naming the culprit."""


class InputError(ValueError):
    """Bad input (file, label, shape, value). The message is one line and names the culprit."""


class ConvergenceError(RuntimeError):
    """A contact iteration that did not converge; the message gives the time and the residual."""
