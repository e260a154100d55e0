"""A mistake in a model description: one line naming the element, the field, the value and what is
allowed (exit code 2, like every bad input)."""
from nsd_core.common.errors import ParameterError


class ModelError(ParameterError):
    """Bad model description (exit code 2)."""
