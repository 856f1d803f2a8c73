"""`python -m cogniframe` = the `cogniframe` command."""

import sys

from .check_cache import quick

code = quick(sys.argv[1:])  # a repeated `check` answered from the cache without importing the CLI
if code is None:
    from .cli import _leave, main

    _leave(main())
sys.exit(code)
