"""What the command modules share: JSON on stdout."""

from __future__ import annotations

import json
from typing import Any


def print_json(obj: Any) -> None:
    """Print ``obj`` as indented JSON with sorted keys.

    Parameters
    ----------
    obj
        A JSON-able object.

    Examples
    --------
    >>> print_json({"b": 1, "a": [1, 2]})
    {
      "a": [
        1,
        2
      ],
      "b": 1
    }
    """
    print(json.dumps(obj, indent=2, sort_keys=True))
