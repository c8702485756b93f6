"""``easylab run --watch``: poll the model and its imports, and replace the
running program when they change (docs/local.md, "Live replacement").

A watcher thread polls the files' modification times and sizes. On a
change it runs the front end; errors are printed and the old program keeps
running; a good model is handed to :meth:`Engine.replace_model`, which
builds its plug-ins (a failure is printed, the old program keeps running)
and swaps it in at the next instant.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path
from typing import Callable

from ..pipeline import lower_file, model_files
from .engine import Engine
from .plugins import PluginError


def _stamp(files: list[Path]) -> tuple:
    stamp = []
    for f in files:
        try:
            st = os.stat(f)
            stamp.append((str(f), st.st_mtime_ns, st.st_size))
        except OSError:
            stamp.append((str(f), None, None))
    return tuple(stamp)


class ModelWatcher(threading.Thread):
    """Polls a model's files every ``interval`` seconds and replaces the
    engine's program when they change; ``say`` prints a message."""

    def __init__(self, path: str, engine: Engine, say: Callable[[str], None], schedule: str | None = None,
                 interval: float = 0.2):
        super().__init__(name="easylab-watch", daemon=True)
        self.path = Path(path)
        self.engine = engine
        self.say = say
        self.schedule = schedule
        self.interval = interval
        self._stop_event = threading.Event()
        self.files = model_files(self.path, engine.program)
        self._last = _stamp(self.files)

    def stop(self) -> None:
        self._stop_event.set()
        self.join()

    def run(self) -> None:
        while not self._stop_event.wait(self.interval):
            stamp = _stamp(self.files)
            if stamp == self._last:
                continue
            # Let an editor finish writing: act when two polls agree.
            if self._stop_event.wait(self.interval):
                return
            stamp = _stamp(self.files)
            self._last = stamp
            self.reload()
            self._last = _stamp(self.files)

    def reload(self) -> None:
        """Run the front end on the model and hand a good result over."""
        running = f"still running program 0x{self.engine.program.program_id:08x}"
        command = f"easylab {self.engine.command}"
        try:
            program, result = lower_file(self.path, self.schedule)
        except (OSError, UnicodeDecodeError) as err:
            self.say(f"{command}: {self.path}: {getattr(err, 'strerror', None) or err}; {running}")
            return
        self.files = model_files(self.path, program)
        if program is None:
            count = len(result.diagnostics.sorted())
            self.say(f"{result.report()}\n{command}: {self.path}: {count} error{'s' if count != 1 else ''}; {running}")
            return
        if self.engine.is_running(program):
            return
        try:
            self.engine.replace_model(program)
        except PluginError as err:
            self.say(f"{command}: error: {err}\n{command}: {running}")
