"""The one exception users see: a plain message, exit code 2, no traceback."""

from __future__ import annotations

class UserError(Exception):
    """Bad input the user can fix (a params file, a data folder, a command-line value).

    The message is one paragraph that names the file, the key and the fix. The CLI prints it
    and exits with code 2; nothing is written to the output folder.

    `key` is the params key path (`frame.width`) a stage blames when it cannot name the file
    itself (a CAD worker only sees a part); `Spec.located` then adds the file and the key's line.
    `located` is True once the message starts with the params file.
    """

    exit_code = 2

    def __init__(self, message: str, key: str | None = None, located: bool = False):
        super().__init__(message)
        self.key = key
        self.located = located

    def __reduce__(self):  # keep key/located across process pools
        return (self.__class__, (str(self), self.key, self.located))


class OutputError(UserError):
    """An output folder or file cogniframe may not touch (foreign files, another build writing)."""


def bug_message(exc: BaseException, command: str) -> str:
    """The paragraph a user sees when cogniframe itself fails (an exception that is not a UserError)."""
    where = ""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    if tb is not None:
        where = f" in {tb.tb_frame.f_code.co_filename.rsplit('/cogniframe/', 1)[-1]}:{tb.tb_lineno}"
    for note in getattr(exc, "__notes__", ()):  # e.g. the build step that failed first
        where += f"; {note}"
    return (f"internal error: this is a bug in cogniframe, not in your input ({type(exc).__name__}: {exc}{where}). "
            f"Nothing was written. Please report it on the cogniframe issue tracker with the command ({command}) and your params "
            f"file; run again with --debug (or COGNIFRAME_DEBUG=1) to print the traceback.")
