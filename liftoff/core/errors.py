"""Errors that carry a one-line, user-facing message naming the culprit."""


class InputError(ValueError):
    """Bad input (file, label, shape, value). The message is one line and names the culprit."""


class ConvergenceError(RuntimeError):
    """A solution that did not converge or diverged; the message gives the time and the residual."""


class ResourceError(RuntimeError):
    """A run that would exceed the machine's memory or a documented size limit; the message
    gives the estimate and how to override or reduce it."""
