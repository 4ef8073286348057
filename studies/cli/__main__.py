"""``python -m studies.cli``: the ``springfem`` command."""

import sys

from . import main

sys.exit(main())
