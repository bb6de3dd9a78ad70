"""Hand slices of the vector environment's step to pool threads that stay awake between steps.

A pool thread that sleeps between steps takes long to wake: on the 2-vCPU virtual machines this
project is benchmarked on, ``ThreadPoolExecutor.submit`` and the future's result took 90-135 µs
when the caller had run Python for 0.1-1 ms before (an ad-hoc timing), a sixth of a step of 4096
sub-environments. So a :class:`Worker`, once it has stepped its slice, keeps polling its mailbox
for the next one, in compiled code without the GIL, for up to a budget of time; then it leaves,
and the next step starts it on a pool thread again. The owner gives a budget only while its steps
come close together (:data:`SPIN_WHEN_GAP_S`): a caller that spends long between steps (a policy's
forward pass) would lose a core to the polling. GNU OpenMP's threads spin the same way before
they sleep; numba's OpenMP threading layer is not used because it kills any process forked after it
has run.

The mailbox is a small int64 array. The owner writes a job (the slice, and the addresses of the
step's actions, active mask and report, which stay alive until the job is done) and then sets the
state with release ordering; the worker reads the state with acquire ordering, steps the slice
through :func:`subenv.envs.transition.step_batch` and sets the state to done. A worker that gives
up compares-and-swaps done for idle, so an owner that posts at the same moment either hands the
job to it or finds it gone and starts another.
"""

from __future__ import annotations

import math
import os
import platform
import time
from collections.abc import Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Final

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from subenv.dynamics._jit import kernel
from subenv.envs.transition import N_REPORT, step_batch

__all__ = ["SPIN_S", "SPIN_WHEN_GAP_S", "Worker"]

SPIN_S: Final = 0.5e-3
"""How long [s] a worker polls for its next slice before it leaves."""
SPIN_WHEN_GAP_S: Final = 0.1e-3
"""Workers poll only while the caller's time between steps (a moving average) is below this [s]: about
what a sleeping thread takes to wake. With a longer gap the polling thread would take a core from the
caller's own work for longer than it saves (at a 0.5 ms threshold, a PyTorch MLP's forward pass
between steps of 1024 sub-environments took 30% longer beside it, an ad-hoc timing)."""

# --- the mailbox ------------------------------------------------------------------------------
STATE, FIRST, STOP, ACTIONS, ACTION_COLUMNS, ACTIVE, REPORT, N_ENVS, BUDGET = range(9)
MAILBOX_SIZE: Final = 16  # (128 bytes: the job's words do not share a cache line with another mailbox)
IDLE, POSTED, RUNNING, DONE = 0, 1, 2, 3


# --- compiled primitives (LLVM's atomics; numba has none) ----------------------------------
def _item_pointer(context: Any, builder: Any, sig: Any, args: Any) -> Any:
    array_type = sig.args[0]
    array = context.make_array(array_type)(context, builder, args[0])
    return cgutils.get_item_pointer(context, builder, array_type, array, [args[1]])


@intrinsic
def _load_acquire(typingctx: Any, array: Any, index: Any) -> Any:
    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        return builder.load_atomic(_item_pointer(context, builder, sig, args), "acquire", 8)

    return types.int64(array, types.intp), codegen


@intrinsic
def _store_release(typingctx: Any, array: Any, index: Any, value: Any) -> Any:
    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        builder.store_atomic(args[2], _item_pointer(context, builder, sig, args), "release", 8)

    return types.void(array, types.intp, types.int64), codegen


@intrinsic
def _compare_exchange(typingctx: Any, array: Any, index: Any, expected: Any, desired: Any) -> Any:
    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        result = builder.cmpxchg(_item_pointer(context, builder, sig, args), args[2], args[3], "acq_rel", "acquire")
        return builder.extract_value(result, 1)

    return types.boolean(array, types.intp, types.int64, types.int64), codegen


_MACHINE: Final = platform.machine().lower()


@intrinsic
def _cpu_relax(typingctx: Any) -> Any:
    """The spin-wait hint (x86 ``pause``, ARM ``yield``): lets a sibling hyperthread run."""

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> None:
        if _MACHINE in ("x86_64", "amd64"):
            pause = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), []),
                                                   "llvm.x86.sse2.pause")
            builder.call(pause, [])
        elif _MACHINE in ("aarch64", "arm64"):
            hint = cgutils.get_or_insert_function(builder.module, ir.FunctionType(ir.VoidType(), [ir.IntType(32)]),
                                                  "llvm.aarch64.hint")
            builder.call(hint, [ir.Constant(ir.IntType(32), 1)])

    return types.void(), codegen


def _pointer_intrinsic(dtype: Any) -> Any:
    @intrinsic
    def pointer(typingctx: Any, address: Any) -> Any:
        def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
            return builder.inttoptr(args[0], context.get_value_type(sig.return_type))

        return types.CPointer(dtype)(types.int64), codegen

    return pointer


_float_pointer = _pointer_intrinsic(types.float64)
_bool_pointer = _pointer_intrinsic(types.boolean)


# --- kernels ------------------------------------------------------------------------------------
@kernel
def serve(mailbox: np.ndarray, rows: np.ndarray, obs: np.ndarray, rngs: numba.typed.List, cfg: np.ndarray,
          hull: np.ndarray) -> None:
    """Step the slices posted to ``mailbox`` until none comes within the job's budget (polls), or
    the owner sets the mailbox idle."""
    waited = 0
    budget = 0
    while True:
        state = _load_acquire(mailbox, STATE)
        if state == POSTED:
            _store_release(mailbox, STATE, RUNNING)
            first, stop, columns, n = mailbox[FIRST], mailbox[STOP], mailbox[ACTION_COLUMNS], mailbox[N_ENVS]
            actions = numba.carray(_float_pointer(mailbox[ACTIONS] + 8 * first * columns), (stop - first, columns))
            active = numba.carray(_bool_pointer(mailbox[ACTIVE] + first), (stop - first,))
            report = numba.carray(_float_pointer(mailbox[REPORT]), (N_REPORT, n))
            budget = mailbox[BUDGET]
            step_batch(rows[first:stop], actions, active, obs[first:stop], rngs, first, cfg, hull, report)
            _store_release(mailbox, STATE, DONE)
            waited = 0
        elif state == DONE:
            waited += 1
            if waited > budget and _compare_exchange(mailbox, STATE, DONE, IDLE):
                return
            _cpu_relax()
        else:  # IDLE: the owner ended the session
            return


@kernel
def post(mailbox: np.ndarray, first: int, stop: int, actions: np.ndarray, active: np.ndarray, report: np.ndarray,
         budget: int) -> bool:
    """Post a job; True if a polling worker took it, False if the mailbox has none (start one)."""
    mailbox[FIRST], mailbox[STOP] = first, stop
    mailbox[ACTIONS], mailbox[ACTION_COLUMNS] = actions.ctypes.data, actions.shape[1]
    mailbox[ACTIVE], mailbox[REPORT], mailbox[N_ENVS] = active.ctypes.data, report.ctypes.data, report.shape[1]
    mailbox[BUDGET] = budget
    if _compare_exchange(mailbox, STATE, DONE, POSTED):
        return True
    _store_release(mailbox, STATE, POSTED)  # (the mailbox was idle: no worker reads it)
    return False


@kernel
def wait_for(mailbox: np.ndarray, taken_only: bool, polls: int) -> bool:
    """Poll until the posted job is taken (``taken_only``) or done, at most ``polls`` times; whether it is."""
    for _ in range(polls):
        state = _load_acquire(mailbox, STATE)
        if state != POSTED and (taken_only or state != RUNNING):
            return True
        _cpu_relax()
    return False


@kernel
def end(mailbox: np.ndarray) -> None:
    """Set the mailbox idle: its worker leaves when it next polls."""
    _store_release(mailbox, STATE, IDLE)


_POLLS_PER_S: list[float] = []


def polls_per_second() -> float:
    """How many polls a waiting worker makes per second (measured once per process)."""
    if not _POLLS_PER_S:
        mailbox = np.zeros(MAILBOX_SIZE, dtype=np.int64)
        mailbox[STATE] = POSTED  # never taken: wait_for polls to its limit
        wait_for(mailbox, False, 1)
        polls = 200_000
        best = math.inf
        for _ in range(3):
            start = time.perf_counter()
            wait_for(mailbox, False, polls)
            best = min(best, time.perf_counter() - start)
        _POLLS_PER_S.append(polls / max(best, 1e-9))
    return _POLLS_PER_S[0]


_WAIT_POLLS: Final = 1 << 16  # (between checks that the worker's thread has not failed)


class Worker:
    """A pool thread's share of a vector environment's steps, through a mailbox.

    ``bound`` (rows, observations, typed list of generators, constants, hull) is fixed for a worker's
    session; :meth:`post` starts a new session when it changes.
    """

    def __init__(self) -> None:
        self._mailbox: np.ndarray | None = None
        self._bound: tuple[Any, ...] = ()
        self._future: Future[None] | None = None
        self._pid = os.getpid()
        self.starts = 0
        """How many times the worker was started on a pool thread (the other posts found it polling)."""

    def post(self, pool: ThreadPoolExecutor, bound: Sequence[Any], piece: slice, actions: np.ndarray,
             active: np.ndarray, report: np.ndarray, spin_s: float) -> None:
        """Step ``piece`` of the rows on the worker's thread.

        ``actions`` (float64, one row per sub-environment), ``active`` (bool) and ``report`` (float64,
        ``(N_REPORT, number of sub-environments)``) are C-contiguous arrays over all sub-environments,
        as :func:`~subenv.envs.transition.step_batch` takes them; they must stay alive until
        :meth:`wait` returns (the worker reads them by address)."""
        if self._pid != os.getpid():  # a forked copy: the worker polling this mailbox is the parent's
            self._mailbox, self._bound, self._future, self._pid = None, (), None, os.getpid()
        if self._mailbox is None or len(bound) != len(self._bound) or any(
                a is not b for a, b in zip(bound, self._bound, strict=True)):
            self.stop()
            self._mailbox = np.zeros(MAILBOX_SIZE, dtype=np.int64)
            self._bound = tuple(bound)
        budget = round(spin_s * polls_per_second()) if spin_s > 0 else 0
        if not post(self._mailbox, piece.start, piece.stop, actions, active, report, budget):
            self._future = pool.submit(serve, self._mailbox, *self._bound)
            self.starts += 1

    def wait(self, taken_only: bool = False) -> None:
        """Until the posted slice is stepped (or, ``taken_only``, until the worker has started it:
        it then no longer needs the GIL)."""
        mailbox = self._mailbox
        if mailbox is None:  # (nothing posted)
            return
        while not wait_for(mailbox, taken_only, _WAIT_POLLS):
            future = self._future
            if future is not None and future.done():
                future.result()  # raises the worker thread's exception
                if not wait_for(mailbox, taken_only, 1):
                    raise RuntimeError("a vector environment's worker thread left without stepping its slice")

    @property
    def polling(self) -> bool:
        """Whether a worker is polling this mailbox for the next slice."""
        return self._mailbox is not None and int(self._mailbox[STATE]) == DONE

    def stop(self) -> Future[None] | None:
        """End the session: the worker leaves when it next polls. Returns its thread's future."""
        future = self._future
        if self._mailbox is not None:
            end(self._mailbox)
        self._mailbox, self._bound, self._future = None, (), None
        return future
