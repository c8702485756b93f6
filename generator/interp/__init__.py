"""Local execution (mode 2): an interpreter of the IR with the actors' C code
in compiled plug-ins (docs/local.md).

- :mod:`.engine`: the LET dispatcher, tasks, channels, devices, live
  replacement (:class:`Engine`, :meth:`Engine.replace_model`);
- :mod:`.dataflow`: SDF schedules over the IR's buffers and external nodes;
- :mod:`.charts`: chart evolution with continuation slots;
- :mod:`.exprs` and :mod:`.values`: typed expressions with the C arithmetic;
- :mod:`.plugins`: actor plug-ins (generation, gcc, cache, ctypes ABI);
- :mod:`.stimulus` and :mod:`.trace`: the host board's file formats;
- :mod:`.watch` and :mod:`.cli`: ``easylab run [--watch]``.
"""

from .engine import Clock, Engine, Replacement
from .plugins import PluginCache, PluginError

__all__ = ["Clock", "Engine", "PluginCache", "PluginError", "Replacement"]
