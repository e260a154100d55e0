"""The errors every layer raises. The layers above subclass them, so one ``except`` at the command
line maps each kind to its exit code whatever layer raised it."""


class InputError(ValueError):
    """Bad input: one line naming the field, the value and what is allowed (exit code 2)."""


class SolverError(RuntimeError):
    """The integrator failed (exit code 3)."""


class ConstraintError(RuntimeError):
    """The loop equations could not be solved (the mechanism cannot follow, or a singular position)."""


class ParameterError(InputError):
    """Bad input: one line naming the field, the value and what is allowed (exit code 2)."""
