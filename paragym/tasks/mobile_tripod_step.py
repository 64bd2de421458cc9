"""The name of before paragym 0.9 of :mod:`paragym.tasks.tripod_step` (one name per task: the tripod's is "tripod").

Importing it gives that module, with a DeprecationWarning; it goes in paragym 1.0.
"""

import sys
import warnings

import paragym.tasks.tripod_step as _module

warnings.warn(f"{__name__} is paragym.tasks.tripod_step since paragym 0.9", DeprecationWarning, stacklevel=2)
sys.modules[__name__] = _module
