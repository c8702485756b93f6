"""Actor plug-ins: each actor specialisation's C code, compiled with gcc into
a shared library on first use, cached, and loaded with ctypes.

The C code of an actor is the firmware's, character for character: the
plug-in source is the actor block of ``templates/model.c.j2`` rendered for
the specialisation's ``SpecView`` (state struct, defines, impl prelude,
start/step/stop functions), followed by a small wrapper that exports the
fixed plug-in ABI (docs/local.md):

.. code-block:: c

    uint32_t el_plugin_abi_version(void);   /* PLUGIN_ABI_VERSION */
    size_t   el_plugin_state_size(void);    /* bytes of one instance's state */
    void     el_plugin_start(void *state);  /* start {{ }} (or nothing) */
    void     el_plugin_step(void *state, const void *const *inputs,
                            void *const *outputs, const void *const *params);
    void     el_plugin_stop(void *state);   /* stop {{ }} (or nothing) */

``inputs[i]`` points at the tokens of the i-th input port (declaration
order), ``outputs[i]`` at room for the i-th output port's tokens, and
``params[i]`` at the value of the i-th run-time parameter (in the
specialisation's ``runtime_params`` order), each in the port's or
parameter's C type. State is zeroed by the caller before ``start``.

A library is cached under a digest of its source, the runtime files it
includes or links, the compiler flags and the compiler's identity
(``gcc --version``), in :func:`cache_dir`; a second run reuses it.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import hashlib
import os
import shutil
import subprocess
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from ..codegen.c_model import SpecView, spec_view as c_spec_view
from ..codegen.render import environment
from ..core.paths import runtime_dir
from ..ir.program import ActorSpec
from .runner import SOURCE as RUNNER_SOURCE, Runner

PLUGIN_ABI_VERSION = 1
COMPILER = "gcc"
# The host board's warnings (so what builds as firmware builds as a plug-in),
# position-independent, only the ABI exported, no undefined symbol left for
# dlopen to find missing.
CFLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", "-D_POSIX_C_SOURCE=200809L",
          "-fPIC", "-shared", "-fvisibility=hidden"]
LDFLAGS = ["-Wl,--no-undefined", "-lm"]
# Runtime files a plug-in includes (headers) or links (the arithmetic).
RUNTIME_HEADERS = ("el_types.h", "el_model.h", "el_dispatch.h")
RUNTIME_SOURCES = ("el_arith.c", "el_wide.c")
# Headers those include, in a plug-in's digest too: a changed one makes
# the cached plug-ins stale.
INCLUDED_HEADERS = ("el_wide.h",)


class PluginError(Exception):
    """An actor plug-in that cannot be built or loaded; the message names the
    actor type and carries the compiler's or loader's own message."""


def cache_dir() -> Path:
    """Where plug-ins are cached: ``$EASYLAB_CACHE``, else
    ``$XDG_CACHE_HOME/easylab/plugins``, else ``~/.cache/easylab/plugins``."""
    if os.environ.get("EASYLAB_CACHE"):
        return Path(os.environ["EASYLAB_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "easylab" / "plugins"


# ====================================================================== source


def spec_view(spec: ActorSpec) -> SpecView:
    """The C backend's view of one specialisation, for a stand-alone file.

    The specialisation is renamed to id 0 and its type's name, and its
    location keeps only the file: the plug-in source, hence its digest and
    its identity across live replacements, depends on what the code is, not
    on where the specialisation sits in the program or its file.
    """
    standalone = dataclasses.replace(spec, id=0, c_name=spec.type_name, location=spec.location.rsplit(":", 1)[0])
    return c_spec_view(standalone)


def _render_actor_block(view: SpecView, part: str) -> str:
    """The firmware's actor code for one specialisation (templates/actor.c.j2,
    which model.c.j2 includes), without the debugger's probe: a plug-in is
    not linked with the debug server. ``part``: "decl" (the state type and
    prototypes) or "code" (the functions, after actor_warnings.c.j2, as at
    the end of model.c)."""
    env = environment()
    block = env.get_template("actor.c.j2").render(s=view, part=part)
    return env.get_template("actor_warnings.c.j2").render() + block if part == "code" else block


def _wrapper(spec: ActorSpec, view: SpecView) -> str:
    """The exported ABI functions around the block's static functions."""
    prefix = f"el_spec{view.spec.id}_{view.spec.c_name}"
    state = view.state_type
    args = [f"({state} *)el_state"]
    n_in = n_out = 0
    for port in spec.ports:
        ctype = port.type.c_name
        if port.direction == "in":
            args.append(f"(const {ctype} *)el_in[{n_in}]" if port.array else f"*(const {ctype} *)el_in[{n_in}]")
            n_in += 1
        else:
            args.append(f"({ctype} *)el_out[{n_out}]")
            n_out += 1
    for index, t in enumerate(spec.runtime_params.values()):
        args.append(f"*(const {t.c_name} *)el_params[{index}]")
    start = f"{prefix}_start(({state} *)el_state);" if view.start else "(void)el_state;"
    stop = f"{prefix}_stop(({state} *)el_state);" if view.stop else "(void)el_state;"
    return f"""
/* ---- EasyLab plug-in ABI {PLUGIN_ABI_VERSION} (docs/local.md) ---- */
#define EL_PLUGIN_EXPORT __attribute__((visibility("default")))
EL_PLUGIN_EXPORT uint32_t el_plugin_abi_version(void);
EL_PLUGIN_EXPORT size_t el_plugin_state_size(void);
EL_PLUGIN_EXPORT void el_plugin_start(void *el_state);
EL_PLUGIN_EXPORT void el_plugin_step(void *el_state, const void *const *el_in, void *const *el_out,
                                     const void *const *el_params);
EL_PLUGIN_EXPORT void el_plugin_stop(void *el_state);

uint32_t el_plugin_abi_version(void) {{ return {PLUGIN_ABI_VERSION}u; }}
size_t el_plugin_state_size(void) {{ return sizeof({state}); }}
void el_plugin_start(void *el_state) {{ {start} }}
void el_plugin_stop(void *el_state) {{ {stop} }}

void el_plugin_step(void *el_state, const void *const *el_in, void *const *el_out, const void *const *el_params)
{{
    (void)el_in;
    (void)el_out;
    (void)el_params;
    {prefix}_step({", ".join(args)});
}}
"""


def plugin_source(spec: ActorSpec) -> str:
    """The complete C source of one specialisation's plug-in."""
    view = spec_view(spec)
    head = (f"/* EasyLab actor plug-in: {spec.type_name} (local execution, docs/local.md).\n"
            f" * Generated from the same template as firmware; do not edit. */\n"
            + "".join(f'#include "{h}"\n' for h in RUNTIME_HEADERS) + "\n")
    return (head + _render_actor_block(view, "decl") + _wrapper(spec, view) + "\n"
            + _render_actor_block(view, "code"))


# ====================================================================== libraries


_STEP_TYPE = [ctypes.c_void_p] * 4

@dataclass
class Plugin:
    """One loaded actor plug-in: the ABI's functions of one specialisation."""

    type_name: str
    digest: str
    path: Path
    state_size: int
    start: ctypes._CFuncPtr
    step: ctypes._CFuncPtr
    stop: ctypes._CFuncPtr
    library: ctypes.CDLL

    @property
    def step_address(self) -> int:
        """The address of ``el_plugin_step`` (for the runner's firings)."""
        return ctypes.cast(self.step, ctypes.c_void_p).value


class PluginCache:
    """Builds, caches and loads plug-ins. ``compiled`` and ``reused`` count
    what this object did (a cache hit on disk is ``reused``)."""

    def __init__(self, directory: Path | None = None, compiler: str = COMPILER):
        self.directory = Path(directory) if directory is not None else cache_dir()
        self.compiler = compiler
        self.compiled = 0
        self.reused = 0
        self._loaded: dict[str, Plugin] = {}
        self._lock = threading.Lock()

    @functools.cached_property
    def compiler_identity(self) -> str:
        """``gcc --version``: a new compiler rebuilds every plug-in."""
        if shutil.which(self.compiler) is None:
            raise PluginError(f"the C compiler '{self.compiler}' is not installed (Debian package: gcc); "
                              "local execution compiles each actor's C code with it")
        proc = subprocess.run([self.compiler, "--version"], capture_output=True, text=True)
        return proc.stdout

    def digest(self, source: str) -> str:
        """The cache key of a plug-in source."""
        h = hashlib.sha256()
        for part in (f"easylab plug-in ABI {PLUGIN_ABI_VERSION}", source, " ".join(CFLAGS + LDFLAGS),
                     self.compiler, self.compiler_identity,
                     *((runtime_dir() / name).read_text(encoding="utf-8")
                       for name in RUNTIME_HEADERS + INCLUDED_HEADERS + RUNTIME_SOURCES)):
            h.update(part.encode("utf-8"))
            h.update(b"\0")
        return h.hexdigest()[:32]

    def load(self, spec: ActorSpec) -> Plugin:
        """The plug-in of one specialisation, built if the cache lacks it."""
        what = f"actor type '{spec.type_name}' ({spec.location})"
        try:
            source = plugin_source(spec)
        except (OSError, ValueError) as err:  # an unreadable or malformed impl file
            raise PluginError(f"{what}: {err}") from None
        digest = self.digest(source)
        with self._lock:
            if digest in self._loaded:
                return self._loaded[digest]
        plugin = self._library(what, source, digest, lambda path: self._open(spec, digest, path))
        with self._lock:
            return self._loaded.setdefault(digest, plugin)

    @functools.cached_property
    def runner(self) -> Runner:
        """The interpreter's runner (runner.c), built and cached like a
        plug-in but not counted as one."""
        def open_runner(path: Path) -> Runner:
            try:
                return Runner(ctypes.CDLL(str(path)))
            except (OSError, AttributeError) as err:
                raise PluginError(f"cannot load the interpreter's runner {path}: {err}") from None
        try:
            source = RUNNER_SOURCE.read_text(encoding="utf-8")
        except OSError as err:
            raise PluginError(f"cannot read the interpreter's runner {RUNNER_SOURCE}: {err.strerror or err}") from None
        return self._library("the interpreter's runner", source, self.digest(source), open_runner, counted=False)

    def _library(self, what: str, source: str, digest: str, open_library, counted: bool = True):
        """``open_library(path)`` of the cached library of ``source``, built
        first if the cache lacks it or holds a damaged one."""
        library = self.directory / f"{digest}.so"
        if library.is_file():
            try:
                opened = open_library(library)
                if counted:
                    with self._lock:
                        self.reused += 1
                return opened
            except PluginError:
                pass  # a damaged cache entry: build it again
        self._compile(what, source, digest, library, counted)
        return open_library(library)

    def load_library(self, what: str, source: str, open_library):
        """``open_library(path)`` of the cached library of another plug-in
        ``source`` (a device's handlers: interp/devices.py), built with the
        actors' flags and counted as a plug-in."""
        return self._library(what, source, self.digest(source), open_library)

    def load_all(self, specs: list[ActorSpec]) -> list[Plugin]:
        """The plug-ins of every specialisation (by spec id), compiled in
        parallel; the first failure (in spec order) is raised."""
        if not specs:
            return []
        self.compiler_identity  # noqa: B018 - fail once, before any thread starts
        with ThreadPoolExecutor(max_workers=min(len(specs), os.cpu_count() or 2)) as pool:
            futures = [pool.submit(self.load, spec) for spec in specs]
            return [f.result() for f in futures]

    def _compile(self, what: str, source: str, digest: str, library: Path, counted: bool) -> None:
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            c_file = self.directory / f"{digest}.c"
            temp = self.directory / f"{digest}.{os.getpid()}.{threading.get_ident()}.tmp"
            temp.write_text(source, encoding="utf-8")
            os.replace(temp, c_file)
        except OSError as err:
            raise PluginError(f"cannot write to the plug-in cache {self.directory}: {err.strerror or err}") from None
        runtime = runtime_dir()
        cmd = [self.compiler, *CFLAGS, f"-I{runtime}", "-o", str(temp), str(c_file),
               *(str(runtime / name) for name in RUNTIME_SOURCES), *LDFLAGS]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            temp.unlink(missing_ok=True)
            raise PluginError(f"{what}: its C code does not compile ({self.compiler}, plug-in source {c_file}):"
                              f"\n{(proc.stdout + proc.stderr).rstrip()}")
        os.replace(temp, library)  # atomic: concurrent runs never see half a library
        if counted:
            with self._lock:
                self.compiled += 1

    def _open(self, spec: ActorSpec, digest: str, library: Path) -> Plugin:
        try:
            lib = ctypes.CDLL(str(library))
            version = lib.el_plugin_abi_version
            size = lib.el_plugin_state_size
            start, step, stop = lib.el_plugin_start, lib.el_plugin_step, lib.el_plugin_stop
        except (OSError, AttributeError) as err:
            raise PluginError(f"actor type '{spec.type_name}': cannot load its plug-in {library}: {err}") from None
        version.restype = ctypes.c_uint32
        version.argtypes = []
        if version() != PLUGIN_ABI_VERSION:
            raise PluginError(f"actor type '{spec.type_name}': plug-in {library} has ABI {version()}, "
                              f"expected {PLUGIN_ABI_VERSION}")
        size.restype = ctypes.c_size_t
        size.argtypes = []
        for fn in (start, stop):
            fn.restype = None
            fn.argtypes = [ctypes.c_void_p]
        step.restype = None
        step.argtypes = _STEP_TYPE
        return Plugin(spec.type_name, digest, library, size(), start, step, stop, lib)
