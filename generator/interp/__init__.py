"""Local execution (mode 2): an interpreter of the IR with the actors' C code
in compiled plug-ins (docs/local.md).

- :mod:`.engine`: the LET dispatcher and the run (:class:`Engine`, live
  replacement with :meth:`Engine.replace_model`);
- :mod:`.state`: one program at run time (items, tasks, channels, devices)
  and its plans, per instant;
- :mod:`.runner`: the plans' operations and their C runner (``runner.c``);
- :mod:`.replacement`: what a live replacement carries over;
- :mod:`.clock`: real time, paced and flat-out virtual time;
- :mod:`.dataflow`: SDF schedules over the IR's buffers and external nodes;
- :mod:`.charts`: chart evolution with continuation slots;
- :mod:`.exprs` and :mod:`.values`: typed expressions with the C arithmetic;
- :mod:`.plugins`: actor plug-ins (generation, gcc, cache, ctypes ABI);
- :mod:`.stimulus` and :mod:`.trace`: the host board's file formats;
- :mod:`.watch` and :mod:`.cli`: ``easylab run [--watch]``.
"""

from .clock import Clock
from .engine import Engine
from .replacement import Replacement
from .plugins import PluginCache, PluginError

__all__ = ["Clock", "Engine", "PluginCache", "PluginError", "Replacement"]
