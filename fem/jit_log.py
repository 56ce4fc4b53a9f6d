"""Keep the form compiler's build log off the user's terminal.

ffcx calls ``logging.basicConfig()`` when imported (a stderr handler on the root logger, no
level), and cffi's build through setuptools sets the root logger to INFO while it compiles:
the first FE run then printed every gcc command line (~90 lines of ``INFO:root:``). The
handler that ffcx added is set to WARNING here, so warnings and errors still show; a user's
own logging configuration (handlers with a level of their own) is left as it is.
"""
from __future__ import annotations

import logging


def quiet_compiler_log() -> None:
    """Raise ffcx's root handler (a level-less stderr StreamHandler) to WARNING."""
    import ffcx  # noqa: F401  (its import adds the handler)

    for handler in logging.root.handlers:
        if type(handler) is logging.StreamHandler and handler.level == logging.NOTSET:
            handler.setLevel(logging.WARNING)
