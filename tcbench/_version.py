"""The installed version of tcbench: a leaf module, so that modules recording it (tracking) need not
import the package's ``__init__`` (which registers every task)."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("tcbench")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0+unknown"
