"""Run a filter: pack Python objects into arrays, call the compiled loop, bundle the result."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters import adaptation
from fuzzynav.filters.adaptation import N_DIAG, context
from fuzzynav.filters.bank_beta import share_control
from fuzzynav.filters.chunk_files import ChunkFiles
from fuzzynav.filters.config import FilterConfig
from fuzzynav.filters.error_st import EM_ST, error_model_code, st_covariance
from fuzzynav.filters.layout import N_CORE
from fuzzynav.filters import loop
from fuzzynav.filters.numba_patch_dispatch import memoise_kernel_addresses
from fuzzynav.filters.result import FilterResult, LocalStates
from fuzzynav.filters.sensor_tables import (concat_event_logs, event_outputs, event_table,
                                            pack_sensors, split_events)
from fuzzynav.nav import strapdown
from fuzzynav.nav.state_layout import LLA_SLICE, NAV_SIZE, Q_SLICE, VEL_SLICE

__all__ = ["InitialState", "run_filter", "FilterRun", "HeldChunks"]

# the kernel tables are the same few tuples run after run: numba types them once (every
# loop's tables: fuzzynav.filters.loop), and looks their kernels' addresses up once
memoise_kernel_addresses()


@dataclass(frozen=True)
class InitialState:
    """The filter's initial navigation state.

    Attributes
    ----------
    time_s : float
        Time of the state (must equal the first IMU sample time).
    lla : (3,) latitude [rad], longitude [rad], height [m].
    vel_n : (3,) ENU velocity [m/s].
    q_bn : (4,) attitude quaternion.
    """

    time_s: float
    lla: np.ndarray
    vel_n: np.ndarray
    q_bn: np.ndarray


def _imu_arrays(imu, nominal: bool = True):
    """The IMU arrays as the loop takes them, checked, and the nominal sample interval
    (``nominal=False``: ``None``, not computed)."""
    time_s = np.ascontiguousarray(imu.time_s, dtype=float)
    dth = np.ascontiguousarray(imu.dtheta_b, dtype=float)
    dv = np.ascontiguousarray(imu.dv_b, dtype=float)
    if time_s.shape != (dth.shape[0] + 1,) or dv.shape != dth.shape:
        raise FuzzynavError(f"IMU arrays disagree: time {time_s.shape}, dtheta {dth.shape}, "
                            f"dv {dv.shape} (time needs one entry more than the increments)")
    step = np.diff(time_s)
    if np.any(step <= 0):
        raise FuzzynavError("IMU sample times must increase strictly")
    return time_s, dth, dv, float(np.median(step)) if nominal else None


def run_filter(imu, sensors, init: InitialState, config: FilterConfig = FilterConfig(),
               adapters=None, sensor_options=None, chunk_samples: int | None = None,
               keep_every: int = 1, on_chunk=None, output_dir=None) -> FilterResult:
    """Run the closed-loop error-state filter.

    Parameters
    ----------
    imu : object
        With ``time_s`` (N+1,), ``dtheta_b`` (N, 3) [rad] and ``dv_b`` (N, 3) [m/s]
        (a :class:`~fuzzynav.sim.trajectory.Trajectory` or a simulated/real IMU log); or
        increments made chunk by chunk: an object with ``chunks(n)`` yielding such
        objects of ``n`` increments each, consecutive, and ``dt_nom_s``, the nominal
        interval [s] (a recording read from its file,
        :class:`~fuzzynav.realdata.loaders.imu_file.ImuCut`), which needs
        ``chunk_samples``.  A feed whose chunks bring their own epochs (a simulation made
        chunk by chunk, :class:`fuzzynav.streamrun.StreamedSource`) has
        ``events_per_chunk = True``: its ``chunks(n)`` yields ``(imu, sensors)`` pairs (the
        streams' epochs of that chunk, :meth:`FilterRun.feed_arrays`), ``sensors`` are then
        the streams' first epochs (their kinds, constants and row layout), and it takes
        ``on_events(logs)`` (each chunk's event logs), ``keep_events`` (keep them in the
        result) and ``chunk_fed(kept)`` after each chunk (``kept()``: its kept outputs).
    sensors : mapping name -> SensorData
        Aiding measurements; each kind needs a registered measurement model.
    init : InitialState
        Initial navigation state at ``imu.time_s[0]``.
    config : FilterConfig
    adapters : mapping name -> Adapter, optional
        Adaptation policy per sensor (default: none, the plain EKF).
    sensor_options : mapping name -> dict, optional
        Options for the measurement models (e.g. ``{"gnss": {"use_velocity": False}}``).
    chunk_samples : int, optional
        Run the loop over consecutive chunks of this many IMU samples (:class:`FilterRun`;
        the same result to the last bit); default one chunk, the whole run.
    keep_every : int
        Keep every ``keep_every``-th recorded output (:class:`FilterRun`).
    on_chunk : callable, optional
        Called with each chunk's :class:`FilterResult` before it is decimated.
    output_dir : path-like, optional
        Write each chunk's kept outputs and event logs there
        (:mod:`~fuzzynav.filters.chunk_files`); only for a feed whose chunks bring their
        own epochs (the event logs are then a chunk's).

    Returns
    -------
    FilterResult

    Raises
    ------
    FuzzynavError
        ``output_dir`` for a run whose event logs are not made chunk by chunk.
    """
    own = bool(getattr(imu, "events_per_chunk", False))
    if output_dir is not None and not own:
        raise FuzzynavError("chunk files (output_dir) are written for a run whose chunks "
                            "bring their own epochs only (streamed from its simulation or "
                            "its file), not for a held one")
    files = None if output_dir is None else ChunkFiles(output_dir)
    if hasattr(imu, "chunks"):
        if chunk_samples is None or int(chunk_samples) < 1:
            raise FuzzynavError("increments made chunk by chunk need chunk_samples >= 1, "
                                f"got {chunk_samples}")
        fr = FilterRun(sensors, init, config, adapters, sensor_options, imu.dt_nom_s,
                       keep_every, on_chunk, events_per_chunk=own,
                       on_events=imu.on_events if own else None,
                       keep_events=imu.keep_events if own else True)
        for piece in imu.chunks(int(chunk_samples)):
            if not own:
                fr.feed(piece)
                continue
            part, epochs = piece
            fr.feed_arrays(*_imu_arrays(part, nominal=False)[:3], epochs)
            imu.chunk_fed(fr.kept)
            if files is not None:
                files.write(fr.kept(), fr.chunk_logs)
        return fr.result()
    held = HeldChunks(imu)
    fr = FilterRun(sensors, init, config, adapters, sensor_options, held.dt_nom_s, keep_every,
                   on_chunk)
    N = held.n_samples
    step = N if chunk_samples is None else int(chunk_samples)
    if step < 1 and N:
        raise FuzzynavError(f"chunk_samples must be a positive number of IMU samples, "
                            f"got {chunk_samples}")
    for piece in held.chunks(max(step, 1)):
        fr.feed_arrays(piece.time_s, piece.dtheta_b, piece.dv_b)
    return fr.result()


class HeldChunks:
    """Held increments (``time_s``, ``dtheta_b``, ``dv_b``), checked once, handed out as
    consecutive chunks of views: how :func:`run_filter` feeds a held run in chunks, and
    what a held run given its epochs chunk by chunk is fed from
    (:class:`fuzzynav.chunk_feed.EpochsByChunk`, ``--output-dir``).  The nominal interval
    is the whole run's median step."""

    def __init__(self, imu):
        self.time_s, self.dtheta_b, self.dv_b, self.dt_nom_s = _imu_arrays(imu)
        self.n_samples = self.dtheta_b.shape[0]
        self.span_s = (float(self.time_s[0]), float(self.time_s[-1]))
        #: the increments held [bytes] (they are not made chunk by chunk)
        self.held_bytes = self.time_s.nbytes + self.dtheta_b.nbytes + self.dv_b.nbytes

    def chunks(self, n: int):
        """Views of ``n`` increments each (their ``n + 1`` times), in order; one empty
        chunk of a run without increments."""
        N = self.n_samples
        for a in range(0, max(N, 1), n):
            b = min(a + n, N)
            yield SimpleNamespace(time_s=self.time_s[a:b + 1], dtheta_b=self.dtheta_b[a:b],
                                  dv_b=self.dv_b[a:b])


class FilterRun:
    """A run of the compiled filter fed its IMU in consecutive chunks.

    Everything the loop keeps between samples (navigation state, error state and
    covariance of every local, adaptation windows and policy states, share-controller
    rings, propagation accumulators, counters: :class:`~fuzzynav.filters.loop.Carry`) is
    carried from one chunk to the next, so feeding a run in chunks of any size gives the
    result of one call over the whole run, to the last bit (:func:`run_filter` is the
    one-chunk case).  The measurement streams are held whole (they are epochs, not IMU
    samples), unless each chunk brings its own (``events_per_chunk``); the recorded outputs of each chunk are handed to ``on_chunk`` and kept
    decimated by ``keep_every``, so memory is bounded by the chunk, the streams and the
    kept outputs.

    Parameters
    ----------
    sensors, init, config, adapters, sensor_options
        As :func:`run_filter`.
    dt_nom_s : float
        Nominal IMU interval [s]; sets the output stride (``config.out_rate_hz``).
    keep_every : int
        Keep recorded output rows ``0, keep_every, 2 keep_every, ...`` of the run.
    on_chunk : callable, optional
        Called with a :class:`FilterResult` of each chunk's recorded outputs (every one,
        before decimation; no events) — e.g. a streaming metric accumulator.
    events_per_chunk : bool
        ``sensors`` are only the streams' first epochs (their kinds, constants and row
        layout); each chunk brings its own epochs (:meth:`feed_arrays`), so the events are
        held one chunk at a time, as a simulation made chunk by chunk has them
        (:mod:`fuzzynav.streamrun`).  The loop's arithmetic is the same.
    on_events : callable, optional
        With ``events_per_chunk``: called with each chunk's event logs (name ->
        :class:`EventLog`).
    keep_events : bool
        With ``events_per_chunk``: keep the chunks' event logs for :meth:`result`
        (concatenated); ``False`` leaves its ``events`` empty.
    """

    def __init__(self, sensors, init: InitialState, config: FilterConfig = FilterConfig(),
                 adapters=None, sensor_options=None, dt_nom_s: float = 0.01,
                 keep_every: int = 1, on_chunk=None, events_per_chunk: bool = False,
                 on_events=None, keep_events: bool = True):
        if int(keep_every) != keep_every or keep_every < 1:
            raise FuzzynavError(f"keep_every must be a positive integer, got {keep_every}")
        self.config, self.keep_every, self.on_chunk = config, int(keep_every), on_chunk
        self.events_per_chunk, self.on_events = bool(events_per_chunk), on_events
        self.keep_events, self.event_parts = bool(keep_events) or not events_per_chunk, []
        self.tb = tb = pack_sensors(dict(sensors), dict(adapters or {}),
                                      dict(sensor_options or {}), config.gate_probability)
        blk_start, blk_kind, blk_inv_tau = config.model.block_arrays()
        self.n = n = config.model.n_states
        self.em = em = error_model_code(config.error_model)
        self.bank, self.state = _bank(config, tb.names, init, em)
        self.stride = max(1, int(round(1.0 / (config.out_rate_hz * dt_nom_s))))
        NL, M = self.bank.beta.size, tb.M
        self.ev = event_outputs(tb.events.t.size, M)
        self.start = loop.Start(strapdown.make_nav(init.lla, init.vel_n, init.q_bn),
                                np.zeros(n - N_CORE))
        self.model = loop.Model(blk_start, blk_kind, blk_inv_tau, em)
        self.events, self.sens = tb.events, tb.sensors
        self.adapt_fns, _ = adaptation.kernel_table(used=tb.sensors.adapt)  # the used ones only
        # the loop without the bank's / the ST model's code when the run has none (cold start)
        self.run_loop = loop.loop_for(NL, em, self.bank.ctl.on)
        self.settings = loop.Settings(float(config.max_prop_dt_s), int(self.stride))
        self.carry = loop.new_carry(n, NL, M, N_DIAG,
                                    context.size(M, tb.events.data.shape[1]))
        self.status, self.stop_t, self.t_end = loop.ST_OK, None, None
        self.parts = []
        #: the last chunk's event logs (``events_per_chunk``)
        self.chunk_logs = {}

    def feed(self, imu) -> None:
        """Run the next chunk: an object with ``time_s`` (N+1,), ``dtheta_b``, ``dv_b``
        (N, 3), starting at the previous chunk's last time."""
        time_s, dth, dv, _ = _imu_arrays(imu)
        self.feed_arrays(time_s, dth, dv)

    def feed_arrays(self, time_s, dth, dv, sensors=None) -> None:
        """:meth:`feed` with checked, contiguous float arrays; with ``events_per_chunk``,
        ``sensors`` are the streams' epochs after the last chunk's end up to this chunk's
        (every epoch in exactly one chunk, as :class:`fuzzynav.sim.stream.Chunk` has them)."""
        if self.t_end is not None and time_s[0] != self.t_end:
            raise FuzzynavError(f"IMU chunk starts at t = {time_s[0]!r} s, not at the previous "
                                f"chunk's last sample time {self.t_end!r} s")
        self.t_end = time_s[-1]
        if self.events_per_chunk:
            self._chunk_events(sensors)
        elif sensors is not None:
            raise FuzzynavError("FilterRun: sensors per chunk need events_per_chunk=True")
        if self.status != loop.ST_OK:  # the run stopped: later chunks record nothing
            self._chunk_done()
            return
        count = self.carry.count
        k0, N, first = int(count[loop.CN_K0]), dth.shape[0], count[loop.CN_STARTED] == 0
        row0 = 0 if first else k0 // self.stride + 1
        rows = (k0 + N) // self.stride - row0 + 1
        count[loop.CN_ROW0] = row0
        NL = self.bank.beta.size
        KL = rows if NL > 1 else 1  # a bank of one records no local outputs
        n = self.n
        out = dict(t=np.full(rows, np.nan), nav=np.empty((rows, NAV_SIZE)),
                   xs=np.empty((rows, n - N_CORE)), sig=np.empty((rows, n)),
                   xl=np.empty((KL, NL, n)), sigl=np.empty((KL, NL, n)),
                   beta=np.empty((KL, NL)))
        status, done = self.run_loop(
            loop.Imu(dth, dv, time_s), self.start, self.model, self.events, self.sens,
            self.bank, self.state, self.tb.meas_fns, self.adapt_fns, self.settings,
            loop.Outputs(**out), loop.EventOutputs(**self.ev), self.carry)
        if status != loop.ST_OK:
            self.status, self.stop_t = status, time_s[done - k0]
        # rows are written in order from the first: the written ones are a prefix
        kept = int(np.count_nonzero(np.isfinite(out["t"])))
        if kept < rows:
            per_row = _PER_ROW + (_PER_LOCAL if NL > 1 else ())
            out = {k: (v[:kept] if k in per_row else v) for k, v in out.items()}
        if self.on_chunk is not None:
            self.on_chunk(_solution(out, self.config, self.state, self.bank.beta))
        if self.keep_every > 1:
            sel = np.flatnonzero((row0 + np.arange(kept)) % self.keep_every == 0)
            per_row = _PER_ROW + (_PER_LOCAL if NL > 1 else ())
            out = {k: (v.take(sel, 0) if k in per_row else v) for k, v in out.items()}
        self.parts.append(out)
        self._chunk_done()

    def _chunk_events(self, sensors) -> None:
        """Make this chunk's event arrays (``events_per_chunk``): the loop's event index
        starts again at 0 on them; its outputs are the chunk's."""
        if sensors is None:
            raise FuzzynavError("FilterRun(events_per_chunk=True) needs each chunk's sensors")
        tb = self.tb
        missing = sorted(set(tb.names) - set(sensors))
        if missing:
            raise FuzzynavError(f"chunk without the stream(s) {', '.join(missing)}")
        rows = [mdl.rows(sensors[nm]) for nm, mdl in zip(tb.names, tb.models)]
        ev = event_table(sensors, tb.names, rows, tb.events.data.shape[1])
        self.events = loop.Events(ev["ev_t"], ev["ev_s"], ev["ev_data"])
        self.chunk_tb = tb._replace(events=self.events)
        self.ev = event_outputs(ev["ev_t"].size, tb.M)
        self.carry.count[loop.CN_EVENT] = 0

    def _chunk_done(self) -> None:
        """Hand a chunk's event logs on (``events_per_chunk``) and keep them if asked."""
        if not self.events_per_chunk:
            return
        logs = self.chunk_logs = split_events(self.ev, self.chunk_tb)
        if self.on_events is not None:
            self.on_events(logs)
        if self.keep_events:
            self.event_parts.append(logs)

    def kept(self, i: int = -1) -> FilterResult:
        """The kept outputs of the ``i``-th chunk fed (no events), e.g. to write them out."""
        return _solution(self.parts[i], self.config, self.state, self.bank.beta)

    def result(self) -> FilterResult:
        """The run's :class:`FilterResult`: the kept outputs of every chunk and the events."""
        if len(self.parts) == 1:
            out = self.parts[0]
        else:
            out = {k: np.concatenate([p[k] for p in self.parts]) for k in self.parts[0]}
        msg = "ok" if self.status == loop.ST_OK else (
            f"stopped at t = {self.stop_t:.2f} s: covariance lost positive definiteness")
        if not self.events_per_chunk:
            events = split_events(self.ev, self.tb)
        elif not self.keep_events:
            events = {}
        else:
            events = {nm: concat_event_logs([p[nm] for p in self.event_parts])
                      for nm in self.tb.names}
        return dataclasses.replace(_solution(out, self.config, self.state, self.bank.beta),
                                   events=events, status=msg)


#: the output arrays with one row per recorded output whatever the bank, and those of a
#: bank of several locals only (a bank of one leaves them placeholders)
_PER_ROW = ("t", "nav", "xs", "sig")
_PER_LOCAL = ("xl", "sigl", "beta")


def _bank(config: FilterConfig, names, init: InitialState, em: int):
    """The loop's :class:`~fuzzynav.filters.loop.Bank` and initial
    :class:`~fuzzynav.filters.loop.BankState`: local ``i`` starts from ``P0 / beta_i`` with
    noise densities ``q / beta_i`` (no bank: the bank of one, every sensor, ``beta = 1``)."""
    spec = config.bank
    if spec is None:
        local, beta, reset, period = np.zeros(max(len(names), 1), np.int64), (1.0,), 1, 0.0
        ctl = share_control(1)
    else:
        local, beta = spec.sensor_locals(names), spec.beta
        reset, period = spec.mode_code(), float(spec.fusion_period_s)
        ctl = share_control(spec.n_local) if spec.controller is None else \
            spec.controller.share_control(spec.n_local)
    P0 = st_covariance(config.P0(), init.vel_n) if em == EM_ST else config.P0()
    b = np.asarray(beta, float)
    n = P0.shape[0]
    # beta = 1 divides exactly: the bank of one starts from the single filter's arrays
    state = loop.BankState(P=np.ascontiguousarray(P0[None] / b[:, None, None]),
                           x=np.zeros((b.size, n)),
                           qd=np.ascontiguousarray(config.q_diag()[None] / b[:, None]),
                           Pg=P0.copy(), xg=np.zeros(n))
    return loop.Bank(local, b.copy(), int(reset), period, ctl), state


def _solution(out, config, state, beta) -> FilterResult:
    """A :class:`FilterResult` of recorded output rows ``out`` (no events)."""
    nav, kept = out["nav"], out["t"].shape[0]
    layout = config.model.layout
    return FilterResult(time_s=out["t"], lla=nav[:, LLA_SLICE], vel_n=nav[:, VEL_SLICE],
                        q_bn=nav[:, Q_SLICE], sensor_states=out["xs"], sigma=out["sig"],
                        state_labels=layout.labels(), layout=layout,
                        locals=_locals(out, slice(None), kept, state, beta))


def _locals(out, keep, kept, state, beta) -> LocalStates:
    """The locals' outputs; a bank of one's are its master's (zero error state after each
    feedback, the fused sigma, a constant share), which the loop leaves unrecorded."""
    if beta.size > 1:
        return LocalStates(out["xl"][keep], out["sigl"][keep], state.P, state.Pg,
                           out["beta"][keep])
    return LocalStates(np.zeros((kept, 1, state.x.shape[1])), out["sig"][keep][:, None, :],
                       state.P, state.Pg, np.full((kept, 1), beta[0]))
