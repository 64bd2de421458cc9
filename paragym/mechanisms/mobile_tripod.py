"""The name of before paragym 0.9 of :mod:`paragym.mechanisms.tripod` (one name per task: the tripod's is "tripod").

Importing it gives that module, with a DeprecationWarning; it goes in paragym 1.0.
"""

import sys
import warnings

import paragym.mechanisms.tripod as _module

warnings.warn(f"{__name__} is paragym.mechanisms.tripod since paragym 0.9", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _module
