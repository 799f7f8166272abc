"""``pluecker.Status``: every status a result can have, named by the core (``pluecker::Status``).

A member is a ``str`` equal to its name (``Status.SUCCESS == "success"``), so results' ``status``
strings and these members compare and print alike; the members come from the extension module, never
from text written here.
"""

from __future__ import annotations

import enum

from ._core import STATUSES

Status = enum.Enum("Status", [(name.upper(), name) for name in STATUSES], type=str, module=__name__)
Status.__doc__ = "Whether an estimate can be used, and if not why (the core's ``Status``; a ``str``)."
# Printed and formatted as the bare name, as the results' ``status`` strings are (on every Python).
Status.__str__ = str.__str__  # type: ignore[method-assign]
Status.__format__ = str.__format__  # type: ignore[method-assign]
