"""The command line: the usage and dispatch of every command (:mod:`.main`), its --help
(:mod:`.help`), the Hydra apps and the checks made before any job starts (:mod:`.app`) and the
quickstart. The commands themselves are the specs of :mod:`tcbench.commands.registry`.

Kept light: ``tcbench --help`` imports none of the scientific libraries. ``tcbench.cli:main`` is
the console script. The name ``main`` here is the function; the module is
``sys.modules["tcbench.cli.main"]`` (``from tcbench.cli.main import ...`` reaches it).
"""

from tcbench.cli.main import COMMANDS, UserError, main

__all__ = ["COMMANDS", "UserError", "main"]
