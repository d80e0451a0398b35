"""``python -m bvsr_cad`` and the ``bvsr`` command (pyproject.toml's entry point names
:func:`console` here).

Until :func:`bvsr_cad.cli.console` takes over, Ctrl-C ends the process quietly with exit status 130:
the command's imports come first, and an interrupt among them would otherwise print a traceback
(the interpreter's own start, before this module runs, is Python's). Only where SIGINT has Python's
default handler (an ignored one, under ``nohup``, stays ignored) and only in a process that runs the
command: a library never imports this module.
"""

import os
import signal


def _interrupted_while_starting(_signum, _frame) -> None:
    os.write(2, b"bvsr: interrupted; nothing was published\n")
    os._exit(130)


_interrupted_while_starting.bvsr_starting = True  # cli.console hands SIGINT back to Python

if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
    signal.signal(signal.SIGINT, _interrupted_while_starting)

from .cli import console  # noqa: E402 - after the handler: this import is the command's slowest

if __name__ == "__main__":
    console()
