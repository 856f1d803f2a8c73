"""The mailboxes the studio's background threads take their work from: the newest job wins, an
older one still waiting is dropped (a page that types fast is checked at its newest edit)."""

from __future__ import annotations

import collections
import threading
from typing import Any


class Latest:
    """A one-slot mailbox: `put` replaces what is waiting; `take` waits for something."""

    def __init__(self):
        self._cond = threading.Condition()
        self._item = None
        self._closed = False

    def put(self, item) -> None:
        with self._cond:
            self._item = item
            self._cond.notify_all()

    def take(self):
        """The waiting item; None once closed (a job still waiting then is dropped: its session
        has ended)."""
        with self._cond:
            while self._item is None and not self._closed:
                self._cond.wait()
            item, self._item = (None if self._closed else self._item), None
            return item

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()


class PerPage:
    """One slot per page: `put` replaces that page's waiting job; `take` hands out the pages'
    jobs in the order they first came, so one busy page cannot starve another."""

    def __init__(self):
        self._cond = threading.Condition()
        self._jobs: collections.OrderedDict[int, Any] = collections.OrderedDict()
        self._closed = False

    def put(self, page: int, job, replace: bool = True) -> None:
        with self._cond:
            if replace or page not in self._jobs:
                self._jobs[page] = job
            self._cond.notify_all()

    def take(self):
        """The next page's job; None once closed (the jobs still waiting are dropped)."""
        with self._cond:
            while not self._jobs and not self._closed:
                self._cond.wait()
            if self._closed:
                self._jobs.clear()
                return None
            return self._jobs.popitem(last=False)[1]

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()
