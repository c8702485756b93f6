"""The backends that generate text from the IR: C for the runtime
(:mod:`.c_model`, :mod:`.c_syntax`), the debug interface's tables and map
(:mod:`.debug`), the service interface's register map and tables
(:mod:`.service`), all rendered together by :mod:`.render`."""
