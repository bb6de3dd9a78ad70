"""Share the vector environment's step between the calling thread and pool threads that stay awake.

Each thread, the caller's included, has a home range of the rows, the same in every step (so its
rows stay in its core's cache), and claims chunks of it from the front (:func:`_claim`); a thread
whose range is done claims chunks of the others' from their back, until no row is left. So the
threads finish together whatever else the machine's cores are doing, and the caller can redraw the
episodes that ended in the middle of the step while the others step its rows
(:meth:`Crew.step`). A chunk is a quarter of what is left of its range (at least :data:`MIN_CHUNK`
rows): few chunks, and small ones at the end. Each sub-environment's results depend on its own row
and generator only, so they do not depend on which thread steps it.

A pool thread that sleeps between steps takes long to wake: on the 2-vCPU virtual machines this
project is benchmarked on, ``ThreadPoolExecutor.submit`` and the future's result took 90-135 µs
when the caller had run Python for 0.1-1 ms before (an ad-hoc timing), a sixth of a step of 4096
sub-environments. So a :class:`Worker`, once it has stepped its chunks, keeps polling its mailbox
for the next step, in compiled code without the GIL, for up to a budget of time; then it leaves,
and the next step starts it on a pool thread again. The owner gives a budget only while its steps
come close together (:data:`SPIN_WHEN_GAP_S`): a caller that spends long between steps (a policy's
forward pass) would lose a core to the polling. GNU OpenMP's threads spin the same way before
they sleep; numba's OpenMP threading layer is not used because it kills any process forked after it
has run.

The mailbox is a small int64 array. The owner writes a job (the addresses of the step's actions,
active mask, report and ranges, which stay alive until the job is done) and then sets the
state with release ordering; the worker reads the state with acquire ordering, takes the job by
compare-and-swap, steps chunks until none is left and sets the state to done. A job that no worker
has taken when the rows have run out is taken back by compare-and-swap (the caller stepped its
share), so the caller never waits for a thread to wake. A worker that gives up polling
compares-and-swaps done for idle, so an owner that posts at the same moment either hands the job to
it or finds it gone and starts another.
"""

from __future__ import annotations

import math
import os
import platform
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Final

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from subenv.dynamics._jit import inline_kernel, kernel
from subenv.envs.transition import N_REPORT, step_batch

__all__ = ["MIN_CHUNK", "SPIN_S", "SPIN_WHEN_GAP_S", "Crew", "Worker"]

SPIN_S: Final = 0.5e-3
"""How long [s] a worker polls for the next step before it leaves."""
SPIN_WHEN_GAP_S: Final = 0.1e-3
"""Workers poll only while the caller's time between steps (a moving average) is below this [s]: about
what a sleeping thread takes to wake. With a longer gap the polling thread would take a core from the
caller's own work for longer than it saves (at a 0.5 ms threshold, a PyTorch MLP's forward pass
between steps of 1024 sub-environments took 30% longer beside it, an ad-hoc timing)."""

# --- the mailbox ------------------------------------------------------------------------------
STATE, N_ENVS, ACTIONS, ACTION_COLUMNS, ACTIVE, REPORT, RANGES, THREADS, HOME, MIN_ROWS, BUDGET, CHUNKS = range(12)
MAILBOX_SIZE: Final = 16  # (128 bytes: the job's words do not share a cache line with another mailbox)
IDLE, POSTED, RUNNING, DONE = 0, 1, 2, 3
RANGE_WORDS: Final = 16  # each range's word of the ranges array on a cache line of its own
_LOW: Final = (1 << 32) - 1  # a range's word: first row (bits 0-31) | end row (bits 32-63)
MIN_CHUNK: Final = 64
"""The smallest chunk of rows a thread claims (one SIMD block of the transition,
:data:`~subenv.dynamics.integrate.LANES`)."""


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
_int_pointer = _pointer_intrinsic(types.int64)


# --- kernels ------------------------------------------------------------------------------------
@inline_kernel
def _claim(ranges: np.ndarray, r: int, own: bool, min_rows: int) -> tuple[int, int]:
    """Claim a chunk ``[start, end)`` of range ``r`` (empty when none is left): from its front for its own
    thread, else from its back. A quarter of what is left, in multiples of ``min_rows``."""
    i = r * RANGE_WORDS
    while True:
        word = _load_acquire(ranges, i)
        lo, hi = word & _LOW, word >> 32
        if lo >= hi:
            return 0, 0
        size = max(min_rows, -(-((hi - lo) // 4) // min_rows) * min_rows)
        if own:
            start, end = lo, min(hi, lo + size)
            new = end | (hi << 32)
        else:
            start, end = max(lo, hi - size), hi
            new = lo | (start << 32)
        if _compare_exchange(ranges, i, word, new):
            return start, end


@inline_kernel
def _step_chunks(ranges: np.ndarray, threads: int, home: int, min_rows: int, max_chunks: int, rows: np.ndarray,
                 actions: np.ndarray, active: np.ndarray, obs: np.ndarray, rngs: numba.typed.List, cfg: np.ndarray,
                 hull: np.ndarray, report: np.ndarray) -> int:
    """Claim and step chunks, of range ``home`` and then of the others, until none is left or
    ``max_chunks`` (-1: no limit) are stepped; how many."""
    stepped = 0
    k = 0
    while k < threads and stepped != max_chunks:
        start, end = _claim(ranges, (home + k) % threads, k == 0, min_rows)
        if start == end:
            k += 1
            continue
        step_batch(rows[start:end], actions[start:end], active[start:end], obs[start:end], rngs, start, cfg, hull,
                   report)
        stepped += 1
    return stepped


@kernel
def share(ranges: np.ndarray, min_rows: int, max_chunks: int, rows: np.ndarray, actions: np.ndarray,
          active: np.ndarray, obs: np.ndarray, rngs: numba.typed.List, cfg: np.ndarray, hull: np.ndarray,
          report: np.ndarray) -> int:
    """The caller's part of a step (its home is range 0): :func:`_step_chunks`."""
    return _step_chunks(ranges, ranges.shape[0] // RANGE_WORDS, 0, min_rows, max_chunks, rows, actions, active, obs,
                        rngs, cfg, hull, report)


@kernel
def serve(mailbox: np.ndarray, rows: np.ndarray, obs: np.ndarray, rngs: numba.typed.List, cfg: np.ndarray,
          hull: np.ndarray) -> None:
    """Step chunks of the steps posted to ``mailbox`` until none comes within the budget (polls) of the
    last one posted, or the owner sets the mailbox idle."""
    waited = 0
    while True:
        state = _load_acquire(mailbox, STATE)
        if state == POSTED:
            if not _compare_exchange(mailbox, STATE, POSTED, RUNNING):
                continue  # (the owner took the job back)
            n, columns = mailbox[N_ENVS], mailbox[ACTION_COLUMNS]
            actions = numba.carray(_float_pointer(mailbox[ACTIONS]), (n, columns))
            active = numba.carray(_bool_pointer(mailbox[ACTIVE]), (n,))
            report = numba.carray(_float_pointer(mailbox[REPORT]), (N_REPORT, n))
            threads = mailbox[THREADS]
            ranges = numba.carray(_int_pointer(mailbox[RANGES]), (threads * RANGE_WORDS,))
            mailbox[CHUNKS] += _step_chunks(ranges, threads, mailbox[HOME], mailbox[MIN_ROWS], -1, rows, actions,
                                            active, obs, rngs, cfg, hull, report)
            _store_release(mailbox, STATE, DONE)
            waited = 0
        elif state == DONE:
            waited += 1
            if waited > mailbox[BUDGET] and _compare_exchange(mailbox, STATE, DONE, IDLE):
                return
            _cpu_relax()
        else:  # IDLE: the owner ended the session
            return


@kernel
def post(mailbox: np.ndarray, ranges: np.ndarray, home: int, min_rows: int, actions: np.ndarray,
         active: np.ndarray, report: np.ndarray, budget: int) -> bool:
    """Post a job; True if a worker polls the mailbox (or is about to), False if it has none (start one)."""
    mailbox[N_ENVS] = report.shape[1]
    mailbox[ACTIONS], mailbox[ACTION_COLUMNS] = actions.ctypes.data, actions.shape[1]
    mailbox[ACTIVE], mailbox[REPORT], mailbox[RANGES] = active.ctypes.data, report.ctypes.data, ranges.ctypes.data
    mailbox[THREADS], mailbox[HOME] = ranges.shape[0] // RANGE_WORDS, home
    mailbox[MIN_ROWS], mailbox[BUDGET] = min_rows, budget
    if _compare_exchange(mailbox, STATE, DONE, POSTED):
        return True
    _store_release(mailbox, STATE, POSTED)  # (the mailbox was idle: no worker reads it)
    return False


@kernel
def take_back(mailbox: np.ndarray) -> bool:
    """Take back a posted job that no worker has taken (as if it were done); whether it was untaken."""
    return _compare_exchange(mailbox, STATE, POSTED, DONE)


@kernel
def wait_for(mailbox: np.ndarray, polls: int) -> bool:
    """Poll until the taken job is done, at most ``polls`` times; whether it is."""
    for _ in range(polls):
        if _load_acquire(mailbox, STATE) != RUNNING:
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
        mailbox[STATE] = RUNNING  # never done: wait_for polls to its limit
        wait_for(mailbox, 1)
        polls = 200_000
        best = math.inf
        for _ in range(3):
            start = time.perf_counter()
            wait_for(mailbox, polls)
            best = min(best, time.perf_counter() - start)
        _POLLS_PER_S.append(polls / max(best, 1e-9))
    return _POLLS_PER_S[0]


_WAIT_POLLS: Final = 1 << 16  # (between checks that the worker's thread has not failed)


class Worker:
    """A pool thread's part of a vector environment's steps, through a mailbox.

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
        self.taken_back = 0
        """How many posted steps the caller took back because they ran out of rows before the worker started."""

    def post(self, pool: ThreadPoolExecutor, bound: Sequence[Any], ranges: np.ndarray, home: int, min_rows: int,
             actions: np.ndarray, active: np.ndarray, report: np.ndarray, spin_s: float) -> None:
        """Step chunks of the rows on the worker's thread: of range ``home`` of ``ranges`` (one per
        thread, :func:`_claim`), then of the others.

        ``actions`` (float64, one row per sub-environment), ``active`` (bool) and ``report`` (float64,
        ``(N_REPORT, number of sub-environments)``) are C-contiguous arrays over all sub-environments,
        as :func:`~subenv.envs.transition.step_batch` takes them; they and ``ranges`` must stay alive
        until :meth:`finish` returns (the worker reads them by address)."""
        if self._pid != os.getpid():  # a forked copy: the worker polling this mailbox is the parent's
            self._mailbox, self._bound, self._future, self._pid = None, (), None, os.getpid()
        if self._mailbox is None or len(bound) != len(self._bound) or any(
                a is not b for a, b in zip(bound, self._bound, strict=True)):
            self.stop()
            self._mailbox = np.zeros(MAILBOX_SIZE, dtype=np.int64)
            self._bound = tuple(bound)
        budget = round(spin_s * polls_per_second()) if spin_s > 0 else 0
        if not post(self._mailbox, ranges, home, min_rows, actions, active, report, budget):
            self._future = pool.submit(serve, self._mailbox, *self._bound)
            self.starts += 1

    @property
    def taken(self) -> bool:
        """Whether the worker has taken the posted job (it then runs compiled code: it does not need the GIL)."""
        return self._mailbox is None or int(self._mailbox[STATE]) != POSTED

    def finish(self) -> None:
        """Once no rows are left to claim: take the job back if the worker has not taken it, else wait until
        it has stepped its last chunk."""
        mailbox = self._mailbox
        if mailbox is None:
            return
        if take_back(mailbox):
            self.taken_back += 1
            return
        while not wait_for(mailbox, _WAIT_POLLS):
            future = self._future
            if future is not None and future.done():
                future.result()  # raises the worker thread's exception
                if not wait_for(mailbox, 1):
                    raise RuntimeError("a vector environment's worker thread left in the middle of a step")

    @property
    def chunks(self) -> int:
        """How many chunks the worker has stepped in this session."""
        return 0 if self._mailbox is None else int(self._mailbox[CHUNKS])

    @property
    def polling(self) -> bool:
        """Whether a worker is polling this mailbox for the next step."""
        return self._mailbox is not None and int(self._mailbox[STATE]) == DONE

    def stop(self) -> Future[None] | None:
        """End the session: the worker leaves when it next polls. Returns its thread's future."""
        future = self._future
        if self._mailbox is not None:
            end(self._mailbox)
        self._mailbox, self._bound, self._future = None, (), None
        return future


class Crew:
    """``workers`` :class:`Worker` s that step the rows of a step with the calling thread, in chunks.

    Parameters
    ----------
    workers : int
        Number of pool threads beside the caller.
    min_rows : int
        The smallest chunk of rows a thread claims.
    """

    def __init__(self, workers: int, min_rows: int = MIN_CHUNK) -> None:
        self.workers = [Worker() for _ in range(workers)]
        self.min_rows = min_rows
        self._ranges = np.zeros((workers + 1) * RANGE_WORDS, dtype=np.int64)
        self._homes = np.zeros(workers + 1, dtype=np.int64)  # each range's word at the start of a step
        self._rows = -1  # (the number of rows _homes is for)

    def step(self, pool: ThreadPoolExecutor, bound: Sequence[Any], actions: np.ndarray, active: np.ndarray,
             report: np.ndarray, spin_s: float, during: Callable[[], None] | None = None) -> None:
        """Step the ``active`` rows of ``bound`` (rows, observations, generators, constants, hull) on the
        workers' threads and this one, with workers that poll for ``spin_s`` after it; run ``during`` (Python
        that holds the GIL, such as resets of rows that are not active) on this thread meanwhile.

        Before ``during``, this thread steps chunks of its range until every worker has taken the step (a
        pool thread needs the GIL to start), then runs ``during`` while they step (and, when done with
        theirs, its range), then steps chunks with them until none is left."""
        rows, obs, rngs, cfg, hull = bound
        ranges, min_rows = self._ranges, self.min_rows
        if rows.shape[0] != self._rows:
            edges = np.linspace(0, rows.shape[0], len(self.workers) + 2).round().astype(np.int64)
            self._homes, self._rows = edges[:-1] | (edges[1:] << 32), rows.shape[0]
        ranges[::RANGE_WORDS] = self._homes  # (published to the workers by the post's release)
        for home, worker in enumerate(self.workers, start=1):
            worker.post(pool, bound, ranges, home, min_rows, actions, active, report, spin_s)
        try:
            if during is not None:
                while not all(worker.taken for worker in self.workers) and share(
                        ranges, min_rows, 1, rows, actions, active, obs, rngs, cfg, hull, report):
                    pass
                during()
            share(ranges, min_rows, -1, rows, actions, active, obs, rngs, cfg, hull, report)
        finally:
            for worker in self.workers:
                worker.finish()

    def stop(self) -> list[Future[None] | None]:
        """Send the workers away (:meth:`Worker.stop`); their threads' futures."""
        return [worker.stop() for worker in self.workers]
