"""The error every layer raises for a bad value from the user, so that the command line and the
API report it as one line naming the field."""
from __future__ import annotations


class InputError(Exception):
    """A bad value from the user: one line naming the field and the value."""

    def __init__(self, field: str, message: str):
        super().__init__(f"{field}: {message}")
        self.field, self.message = field, message
