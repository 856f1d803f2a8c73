"""The one exception users see: a plain message, exit code 2, no traceback."""

from __future__ import annotations


class UserError(Exception):
    """Bad input the user can fix (a params file, a data folder, a command-line value).

    The message is one paragraph that names the file, the key and the fix. The CLI prints it
    and exits with code 2; nothing is written to the output folder.
    """

    exit_code = 2
