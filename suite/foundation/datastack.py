"""Frame-stack chunks kept for reuse: a work-around of CPython issue gh-142183.

Since 3.11, CPython keeps the frames of Python calls on a per-thread stack of chunks of 16 KiB
(``Python/pystate.c``: ``push_chunk``, ``_PyThreadState_PopFrame``). A call that does not fit
in the current chunk maps a new one (``_PyObject_VirtualAlloc``, by default an ``mmap``), and the
return that empties it unmaps it at once. A loop that calls a function just across that edge
maps, faults in and unmaps a chunk on every call. numba's compiler does exactly this when the
edge falls inside one of its recursive walks over a function's IR: compiling the kernels of
``tests/cell/test_time_grid.py`` from an empty cache took 3.5 million page faults and 20 s of system
time out of 90 s (``perf stat``, CPython 3.11.7, 2026-11-27). CPython fixed it in 2026 by keeping
one freed chunk per thread (python/cpython#145789, 3.13 and 3.14 backports); 3.11 and 3.12 only
get security fixes.

:func:`install` does the same from outside: the chunks are allocated through the *arena
allocator* (``PyObject_SetArenaAllocator``, a public C API), so gnibench puts in front of it two
small functions, compiled from the LLVM IR below by llvmlite (numba's own LLVM binding, no C
compiler needed):

* ``chunk_free`` keeps up to 8 freed blocks of at most 64 KiB (chunks: the interpreter's
  arenas of obmalloc are 1 MiB and are always passed on) instead of unmapping them;
* ``chunk_alloc`` returns the last block kept when the size asked is its size (chunks are freed
  and allocated again in stack order), else asks the previous allocator.

Every block therefore comes from the previous allocator and goes back to it, whatever was
allocated before :func:`install`; a reused chunk is not zeroed, as in CPython's own fix (a frame
initialises what it uses). Arena calls are made with the GIL held, so the two globals need no
lock. Measured on ``tests/cell/test_time_grid.py`` from an empty kernel cache: 90.2 s -> 70.3 s of
CPU, 3.47 million -> 0.68 million page faults, system time 19.9 s -> 1.8 s.

Installed by the command line, the Python API, the kernels' loader and the test processes (forked
workers inherit it) (:func:`install` is idempotent and a no-op where it does not apply: another
interpreter than CPython 3.11-3.13 with the GIL, or llvmlite missing or on an LLVM older than 15).
``GNIBENCH_FRAME_CACHE=0`` turns it off; a value other than 0 or 1 is refused before any work
(:func:`check_setting`, from the commands' check of the environment,
:func:`gnibench.suite.foundation.budgets.check_limits`).
"""
from __future__ import annotations

import os
import sys

__all__ = ["install", "installed"]

#: the largest block kept (bytes): a chunk of the frame stack is 16 KiB, or one frame when larger
KEEP_AT_MOST = 65536
#: how many freed blocks are kept, last freed first reused: calls that oscillate across several
#: chunk edges at once (a deep recursion entered again and again) unmap nothing either
KEPT = 8

IR = r"""
@old_ctx = global ptr null
@old_alloc = global ptr null
@old_free = global ptr null
@kept = global [KEPT x ptr] zeroinitializer
@kept_size = global [KEPT x i64] zeroinitializer
@count = global i64 0

define ptr @chunk_alloc(ptr %ctx, i64 %size) {
entry:
  %n = load i64, ptr @count
  %any = icmp ugt i64 %n, 0
  br i1 %any, label %check, label %ask
check:
  %top = sub i64 %n, 1
  %sp = getelementptr [KEPT x i64], ptr @kept_size, i64 0, i64 %top
  %s = load i64, ptr %sp
  %same = icmp eq i64 %s, %size
  br i1 %same, label %give, label %ask
give:
  %pp = getelementptr [KEPT x ptr], ptr @kept, i64 0, i64 %top
  %p = load ptr, ptr %pp
  store i64 %top, ptr @count
  ret ptr %p
ask:
  %oc = load ptr, ptr @old_ctx
  %oa = load ptr, ptr @old_alloc
  %r = call ptr %oa(ptr %oc, i64 %size)
  ret ptr %r
}

define void @chunk_free(ptr %ctx, ptr %p, i64 %size) {
entry:
  %n = load i64, ptr @count
  %room = icmp ult i64 %n, KEPT
  %small = icmp ule i64 %size, KEEP_AT_MOST
  %keep = and i1 %room, %small
  br i1 %keep, label %stash, label %pass
stash:
  %pp = getelementptr [KEPT x ptr], ptr @kept, i64 0, i64 %n
  store ptr %p, ptr %pp
  %sp = getelementptr [KEPT x i64], ptr @kept_size, i64 0, i64 %n
  store i64 %size, ptr %sp
  %n1 = add i64 %n, 1
  store i64 %n1, ptr @count
  ret void
pass:
  %oc = load ptr, ptr @old_ctx
  %of = load ptr, ptr @old_free
  call void %of(ptr %oc, ptr %p, i64 %size)
  ret void
}
""".replace("KEEP_AT_MOST", str(KEEP_AT_MOST)).replace("KEPT", str(KEPT))

_engine = None          # the compiled functions live as long as the process


def applies() -> bool:
    """CPython 3.11-3.13 with the GIL, and not turned off by ``GNIBENCH_FRAME_CACHE=0``."""
    import sysconfig

    return (sys.implementation.name == "cpython" and (3, 11) <= sys.version_info[:2] <= (3, 13)
            and not sysconfig.get_config_var("Py_GIL_DISABLED")
            and os.environ.get("GNIBENCH_FRAME_CACHE", "1").strip() != "0")


def llvm_reads_opaque_pointers() -> bool:
    """The IR above writes opaque pointers (``ptr``), which llvmlite's LLVM reads from version 15
    on; with an older one :func:`install` does nothing."""
    try:
        import llvmlite.binding as llvm

        return tuple(llvm.llvm_version_info) >= (15,)
    except Exception:                                   # noqa: BLE001
        return False


def check_setting(environ=None) -> None:
    """Refuse a value of ``GNIBENCH_FRAME_CACHE`` other than unset, empty, 0 or 1 (``off`` or
    ``false`` would silently keep the cache on)."""
    from gnibench.suite.foundation.errors import UserError

    text = (os.environ if environ is None else environ).get("GNIBENCH_FRAME_CACHE")
    if text is not None and text.strip() not in ("", "0", "1"):
        raise UserError(f"bad GNIBENCH_FRAME_CACHE={text!r}; allowed: unset, 0 (off) or 1 (on)")


def installed() -> bool:
    return _engine is not None


def install() -> bool:
    """Put the chunk cache in front of the arena allocator, once per process; True when it is
    (now or before). Any failure leaves the interpreter as it was and returns False."""
    global _engine
    if _engine is not None:
        return True
    if not applies() or not llvm_reads_opaque_pointers():
        return False
    try:
        import ctypes

        import llvmlite.binding as llvm

        class Arena(ctypes.Structure):             # PyObjectArenaAllocator (cpython/objimpl.h)
            _fields_ = [("ctx", ctypes.c_void_p), ("alloc", ctypes.c_void_p),
                        ("free", ctypes.c_void_p)]

        llvm.initialize_native_target()
        llvm.initialize_native_asmprinter()
        module = llvm.parse_assembly(IR)
        module.verify()
        machine = llvm.Target.from_default_triple().create_target_machine()
        engine = llvm.create_mcjit_compiler(module, machine)
        engine.finalize_object()
        old = Arena()
        ctypes.pythonapi.PyObject_GetArenaAllocator(ctypes.byref(old))
        for name, value in (("old_ctx", old.ctx), ("old_alloc", old.alloc),
                            ("old_free", old.free)):
            ctypes.c_void_p.from_address(engine.get_global_value_address(name)).value = value
        new = Arena(None, engine.get_function_address("chunk_alloc"),
                    engine.get_function_address("chunk_free"))
        if not (old.alloc and old.free and new.alloc and new.free):
            return False
        _engine = engine                      # kept before the interpreter can call into it
        ctypes.pythonapi.PyObject_SetArenaAllocator(ctypes.byref(new))
        return True
    except Exception:                                   # noqa: BLE001 - an optimisation only
        return False
