"""ctypes bindings of the FMU's FMI 2.0 and FMI 3.0 functions behind one small interface.

Both standards' calls are reached through :class:`Fmi2` and :class:`Fmi3`, which share method
names (``enter_init``, ``get``, ``do_step``, ``get_state`` ...), so that one executor can drive
either. Every method returns the FMI status (0 OK, 1 Warning, 2 Discard, 3 Error, 4 Fatal) and,
for getters, the values. Memory comes from the C library's calloc/free, so that in a process with
AddressSanitizer preloaded every allocation the FMU makes through the callbacks is checked.
"""

from tests.fuzz.binding_base import DISCARD, ERROR, FATAL, OK, WARNING
from tests.fuzz.fmi2_binding import Fmi2, _Fmi2EventInfo
from tests.fuzz.fmi3_binding import Fmi3, _Fmi3Intermediate

__all__ = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "Fmi2", "Fmi3", "_Fmi2EventInfo", "_Fmi3Intermediate"]
