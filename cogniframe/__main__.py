"""`python -m cogniframe` = the `cogniframe` command."""

from .cli import entry

entry()
