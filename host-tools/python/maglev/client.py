"""Stage: a Modbus client for the maglev stage controller (RTU or TCP, pymodbus).

Registers are read and written by their registers.def names; values are SI
(m, rad, A, Hz, s) as in docs/REGISTERS.md. Host commands go through the
cmd.axis / cmd.value / cmd.code registers in one 0x17 request that reads
cmd.result back, the same path stagectl uses.
"""
import contextlib
import math
import time
from typing import Callable, Dict, Iterable, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from . import errors
from .recording import FrfResult, Recording, sine_fit
from .registers import (AXES, ENGINEER_KEY, HOST_COMMANDS, LAB_SIGNALS, POSE_REGISTERS, ROTATIONAL_AXES, REGISTERS,
                        CommandResult, CouplingCalibrationResult, FaultCode, Register, SequencerState, register)

# The most registers one 0x03 request may read (Modbus application protocol).
_MAX_READ_WORDS = 125

# The pose/status block every watcher and poller wants (one contiguous read).
STATUS_NAMES = ("status.state", "status.fault", "status.moving", "status.x", "status.y", "status.z",
                "status.theta_x", "status.theta_y", "status.theta_z", "status.scale_k")


# Every address the map serves: a read may span a gap between wanted
# registers only when each address in between is mapped (else exception 02).
# A download window (type "block") is never read as a filler.
_MAPPED = frozenset(a for r in REGISTERS.values() if r.type != "block"
                    for a in range(r.address, r.address + r.width))


def _blocks(regs: Sequence[Register]) -> List[List[Register]]:
    """Group registers into runs that one 0x03 request can read: at most 125 words,
    no unmapped address inside (the words between wanted registers are read and
    dropped)."""
    runs: List[List[Register]] = []
    for r in sorted(set(regs), key=lambda r: r.address):
        if runs:
            last = runs[-1][-1]
            gap = range(last.address + last.width, r.address)
            span = r.address + r.width - runs[-1][0].address
            if span <= _MAX_READ_WORDS and all(a in _MAPPED for a in gap):
                runs[-1].append(r)
                continue
        runs.append([r])
    return runs


def _axis_index(axis) -> int:
    if isinstance(axis, int) and 0 <= axis < len(AXES):
        return axis
    try:
        return AXES.index(axis)
    except ValueError:
        raise errors.ValueOutOfRange(f"unknown axis {axis!r} (one of {', '.join(AXES)})") from None


class CalibrationResult(NamedTuple):
    """How the kernel's coupling calibration ended (status.calibration, .coupling_before /
    _after: the largest scaled off-diagonal coupling identified before the correction and
    measured again with it applied)."""
    result: CouplingCalibrationResult
    coupling_before: float
    coupling_after: float


class Stage:
    """One connection to a stage controller.

    Stage.tcp("127.0.0.1", 1502) or Stage.rtu("/dev/ttyUSB0", 115200); use it
    as a context manager (the engineer key is never left written).
    """

    def __init__(self, client, unit: int = 1, description: str = ""):
        self._client = client
        self.unit = unit
        self.description = description
        if not client.connect():
            raise errors.CommunicationError(f"cannot connect to {description or client}")

    @classmethod
    def tcp(cls, host: str, port: int = 502, unit: int = 1, timeout_s: float = 1.0) -> "Stage":
        from pymodbus.client import ModbusTcpClient

        return cls(ModbusTcpClient(host, port=port, timeout=timeout_s, retries=0), unit, f"{host}:{port}")

    @classmethod
    def rtu(cls, device: str, baudrate: int = 115200, unit: int = 1, timeout_s: float = 1.0) -> "Stage":
        from pymodbus.client import ModbusSerialClient
        from pymodbus.framer.rtu_framer import ModbusRtuFramer

        client = ModbusSerialClient(device, framer=ModbusRtuFramer, baudrate=baudrate, bytesize=8, parity="N",
                                    stopbits=1, timeout=timeout_s, retries=0)
        return cls(client, unit, f"{device},{baudrate}")

    def close(self) -> None:
        self._client.close()

    def __enter__(self) -> "Stage":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ---- transport -------------------------------------------------------------
    def _write_read(self, write_address: int, words: Sequence[int], read_address: int, read_count: int,
                    what: str) -> List[int]:
        """One 0x17 (write, then read, multiple registers) to this unit."""
        from pymodbus.register_read_message import ReadWriteMultipleRegistersRequest

        request = ReadWriteMultipleRegistersRequest(read_address=read_address, read_count=read_count,
                                                    write_address=write_address, write_registers=list(words))
        # readwrite_registers() of pymodbus 3.0 drops slave= (the request went to
        # unit 0, an RTU broadcast nobody answers): address the request itself
        # (3.0 calls it unit_id, later versions slave_id).
        request.unit_id = self.unit
        request.slave_id = self.unit
        return list(self._execute(lambda: self._client.execute(request), what, 0x17).registers)

    def _execute(self, call: Callable, what: Optional[str], function: int):
        try:
            response = call()
        except errors.MaglevError:
            raise
        except Exception as e:  # pymodbus raises ModbusException / ConnectionException / socket errors
            raise errors.CommunicationError(f"{what or 'request'}: {e}") from e
        code = getattr(response, "exception_code", None)
        if code is not None and response.isError():
            raise errors.modbus_exception(code, what, function)
        if response.isError():
            raise errors.CommunicationError(f"{what or 'request'}: {response}")
        return response

    def read_words(self, address: int, count: int, what: Optional[str] = None) -> List[int]:
        """Raw holding registers (function 0x03)."""
        r = self._execute(lambda: self._client.read_holding_registers(address, count, slave=self.unit), what, 0x03)
        return list(r.registers)

    def write_words(self, address: int, words: Sequence[int], what: Optional[str] = None) -> None:
        """Raw write multiple registers (function 0x10)."""
        self._execute(lambda: self._client.write_registers(address, list(words), slave=self.unit), what, 0x10)

    # ---- registers by name -------------------------------------------------------
    def read(self, name: str) -> float:
        """One register's value (int for u16/i32, float for f32), SI units."""
        r = register(name)
        return r.decode(self.read_words(r.address, r.width, name))

    def read_many(self, names: Iterable[str]) -> Dict[str, float]:
        """Several registers, in as few requests as contiguous addresses allow."""
        regs = [register(n) for n in names]
        out = self._read_runs(_blocks(regs))
        return {r.name: out[r.name] for r in regs}

    def _read_runs(self, runs: List[List[Register]]) -> Dict[str, float]:
        """One 0x03 request per run (see _blocks), decoded by name."""
        out: Dict[str, float] = {}
        for run in runs:
            base = run[0].address
            words = self.read_words(base, run[-1].address + run[-1].width - base, run[0].name)
            for r in run:
                out[r.name] = r.decode(words[r.address - base:r.address - base + r.width])
        return out

    def write(self, name: str, value: float) -> None:
        """Write one register. Checked here first (ValueOutOfRange, nothing sent); the
        controller checks again (IllegalDataValue, ServerDeviceBusy, IllegalFunction, ...)."""
        r = register(name)
        if r.access == "read-only":
            raise errors.ValueOutOfRange(f"{name} is read-only")
        if not r.in_range(float(value)):
            raise errors.ValueOutOfRange(f"{name}: {value!r} is outside [{r.min:g}, {r.max:g}] {r.unit}".rstrip()
                                         + (" or not an integer" if r.type != "f32" else ""))
        self.write_words(r.address, r.encode(value), name)

    def write_block(self, values: Dict[str, float]) -> None:
        """Write registers that cover one contiguous address range in ONE 0x10 request
        (the controller checks and applies it as a whole); each value is checked here
        first (ValueOutOfRange, nothing sent)."""
        regs = sorted((register(n) for n in values), key=lambda r: r.address)
        words: List[int] = []
        for a, b in zip(regs, regs[1:] + [None]):
            v = values[a.name]
            if a.access == "read-only" or not a.in_range(float(v)):
                raise errors.ValueOutOfRange(f"{a.name}: {v!r} is read-only or outside [{a.min:g}, {a.max:g}]")
            words.extend(a.encode(v))
            if b is not None and b.address != a.address + a.width:
                raise errors.ValueOutOfRange(f"write_block: {a.name} and {b.name} are not adjacent")
        self.write_words(regs[0].address, words, regs[0].name)

    @contextlib.contextmanager
    def engineer(self):
        """Engineer access for the block (writes access.key; locks again on exit)."""
        self.write("access.key", ENGINEER_KEY)
        try:
            yield self
        finally:
            with contextlib.suppress(errors.MaglevError):
                self.write("access.key", 0)

    # ---- status ------------------------------------------------------------------
    def state(self) -> SequencerState:
        return SequencerState(self.read("status.state"))

    def fault(self) -> FaultCode:
        return FaultCode(self.read("status.fault"))

    def pose(self) -> Dict[str, float]:
        """Measured pose by axis name (m, rad)."""
        v = self.read_many(POSE_REGISTERS.values())
        return {axis: v[name] for axis, name in POSE_REGISTERS.items()}

    def status(self) -> Dict[str, float]:
        """The status block (state, fault, moving, pose, scale_k) in one read."""
        return self.read_many(STATUS_NAMES)

    # ---- commands ----------------------------------------------------------------
    def command(self, name: str, axis=0, value: float = 0.0) -> CommandResult:
        """Issue host command ``name`` (kHostCommandSpecs: home, levitate, land, stop,
        clear_fault, hold, step, move_to, ...). Over Modbus a command carries the axis
        and one value; CommandRejected when cmd.result is not 0 (accepted)."""
        try:
            spec = HOST_COMMANDS[name]
        except KeyError:
            raise errors.ValueOutOfRange(f"unknown command {name!r} (one of {', '.join(HOST_COMMANDS)})") from None
        ax = _axis_index(axis)
        value_reg = register("cmd.value")
        if not value_reg.in_range(float(value)):
            raise errors.ValueOutOfRange(f"cmd.value: {value!r} is outside [{value_reg.min:g}, {value_reg.max:g}]")
        words = [ax, *value_reg.encode(value), spec.code]
        base = register("cmd.axis").address
        assert register("cmd.code").address == base + 3  # the one-request layout stagectl uses too
        result = CommandResult(self._write_read(base, words, register("cmd.result").address, 1,
                                                f"cmd.code ({name})")[0])
        if result != CommandResult.ACCEPTED:
            raise errors.CommandRejected(name, result)
        return result

    def wait_state(self, target: SequencerState, timeout_s: float = 30.0,
                   progress: Optional[Callable[[SequencerState, float], None]] = None,
                   interval_s: float = 0.02) -> float:
        """Wait until status.state == target; returns the seconds waited.
        StageFaulted if the stage faults, WaitTimeout after ``timeout_s``.
        ``progress(state, elapsed_s)`` is called whenever the state changes."""
        t0 = time.monotonic()
        last = None
        while True:
            v = self.read_many(("status.state", "status.fault"))
            state = SequencerState(v["status.state"])
            elapsed = time.monotonic() - t0
            if progress is not None and state != last:
                progress(state, elapsed)
            last = state
            if state == target:
                return elapsed
            if state == SequencerState.FAULT and target != SequencerState.FAULT:
                raise errors.StageFaulted(FaultCode(v["status.fault"]), target.name)
            if elapsed > timeout_s:
                raise errors.WaitTimeout(f"state {state.name} after {timeout_s:g} s, waiting for {target.name}")
            time.sleep(interval_s)

    def wait_motion_done(self, timeout_s: float = 30.0, interval_s: float = 0.01) -> float:
        """Wait until status.moving is 0; returns the seconds waited."""
        t0 = time.monotonic()
        while self.read("status.moving") != 0:
            if time.monotonic() - t0 > timeout_s:
                raise errors.WaitTimeout(f"still moving after {timeout_s:g} s")
            time.sleep(interval_s)
        return time.monotonic() - t0

    def home(self, wait: bool = True, timeout_s: float = 30.0, progress=None) -> None:
        """Hall homing (landed); with ``wait``, until it is back in Idle."""
        self.command("home")
        if wait:
            time.sleep(0.05)  # Idle -> Homing happens on the next servo ticks
            self.wait_motion_done(timeout_s)
            self.wait_state(SequencerState.IDLE, timeout_s, progress)

    def levitate(self, wait: bool = True, timeout_s: float = 30.0, progress=None) -> None:
        """Start-up sequence; with ``wait``, until Ready."""
        self.command("levitate")
        if wait:
            self.wait_state(SequencerState.READY, timeout_s, progress)

    def land(self, wait: bool = True, timeout_s: float = 30.0, progress=None) -> None:
        self.command("land")
        if wait:
            self.wait_state(SequencerState.IDLE, timeout_s, progress)

    def stop(self) -> None:
        self.command("stop")

    def hold(self) -> None:
        self.command("hold")

    def clear_fault(self) -> None:
        self.command("clear_fault")

    def step(self, axis, delta: float) -> None:
        """Reference step of ``delta`` (m or rad) on ``axis`` (kernel limit 100 um / 10-20 urad)."""
        self.command("step", axis, delta)

    def move_to(self, axis, target: float, wait: bool = True, timeout_s: float = 30.0) -> None:
        """Trapezoidal move to ``target`` at the axis' max_velocity / max_acceleration."""
        self.command("move_to", axis, target)
        if wait:
            self.wait_motion_done(timeout_s)

    def move_by(self, axis, distance: float, wait: bool = True, timeout_s: float = 30.0) -> None:
        """Move by ``distance`` from the measured position (a move_to: Modbus carries one value)."""
        name = AXES[_axis_index(axis)]
        self.move_to(axis, self.read(POSE_REGISTERS[name]) + distance, wait, timeout_s)

    def calibrate_coupling(self, wait: bool = True, timeout_s: float = 90.0,
                           progress: Optional[Callable[[int, float], None]] = None) -> Optional[CalibrationResult]:
        """The kernel's coupling calibration (cmd.code 17; Ready only, ~28 s; docs/KERNEL.md
        "Coupling calibration"). CommandRejected when refused (not Ready, busy). With ``wait``,
        until it ends: ``progress(experiment, elapsed_s)`` at each of its 12 experiments; returns
        the CalibrationResult when it passed (the correction acts; save() keeps it), raises
        CalibrationFailed when the kernel kept the old correction, WaitTimeout after ``timeout_s``.
        status.calibration keeps the last run's result until the kernel takes the command on its
        next tick: an end is read once this run was seen running, or after 0.2 s."""
        self.command("calibrate_coupling")
        if not wait:
            return None
        t0 = time.monotonic()
        seen_running = False
        last_step = None
        while True:
            v = self.read_many(("status.calibration", "status.calibration_step"))
            result = CouplingCalibrationResult(int(v["status.calibration"]))
            elapsed = time.monotonic() - t0
            if result == CouplingCalibrationResult.RUNNING:
                seen_running = True
                step = int(v["status.calibration_step"])
                if progress is not None and step != last_step:
                    progress(step, elapsed)
                last_step = step
            elif seen_running or elapsed >= 0.2:
                break
            if elapsed > timeout_s:
                raise errors.WaitTimeout(f"coupling calibration still running after {timeout_s:g} s")
            time.sleep(0.05)
        c = self.read_many(("status.coupling_before", "status.coupling_after"))
        out = CalibrationResult(result, c["status.coupling_before"], c["status.coupling_after"])
        if result != CouplingCalibrationResult.PASSED:
            raise errors.CalibrationFailed(out)
        return out

    # ---- host-side data acquisition -------------------------------------------
    def poll(self, names: Iterable[str] = STATUS_NAMES, duration_s: float = 1.0, rate_Hz: float = 500.0,
             at: Sequence[Tuple[float, Callable[[], None]]] = ()) -> Recording:
        """HOST-SIDE polling: read ``names`` at ``rate_Hz`` for ``duration_s`` into numpy
        arrays. Each sample is stamped with the host's monotonic clock at the middle of
        its read request, so the sample times carry the link's jitter (Modbus TCP on
        localhost: a read takes ~0.5 ms; RTU at 115200 baud ~5 ms): the recording is
        only as regular as the link. ``at``: (time_s, action) pairs run between samples
        once their time has come (e.g. a step command), their times recorded in
        Recording.events."""
        names = tuple(names)
        regs = [register(n) for n in names]
        runs = _blocks(regs)
        period = 1.0 / rate_Hz
        pending = sorted(at, key=lambda a: a[0])
        t_list: List[float] = []
        rows: List[List[float]] = []
        events: List[Tuple[float, str]] = []
        t0 = time.monotonic()
        next_t = t0
        while True:
            now = time.monotonic()
            if now - t0 >= duration_s:
                break
            while pending and now - t0 >= pending[0][0]:
                _, action = pending.pop(0)
                ta = time.monotonic()
                action()
                events.append(((ta + time.monotonic()) / 2 - t0, getattr(action, "__name__", "action")))
            ta = time.monotonic()
            values = self._read_runs(runs)
            t_list.append((ta + time.monotonic()) / 2 - t0)
            rows.append([values[n] for n in names])
            next_t += period
            sleep = next_t - time.monotonic()
            if sleep > 0:
                time.sleep(sleep)
            else:
                next_t = time.monotonic()  # cannot keep up: sample as fast as the link allows
        data = np.array(rows, dtype=float).reshape(len(rows), len(names))
        return Recording(np.array(t_list), {n: data[:, i] for i, n in enumerate(names)}, events)

    def step_response(self, axis, delta: float, duration_s: float = 0.5, pre_s: float = 0.05,
                      rate_Hz: float = 1000.0, names: Optional[Iterable[str]] = None) -> Recording:
        """Poll (host side) around a reference step of ``delta`` on ``axis``: ``pre_s`` of
        rest, the step, then until ``duration_s``. Recording.events[0] is the step time."""
        name = AXES[_axis_index(axis)]
        names = tuple(names) if names is not None else (POSE_REGISTERS[name], "status.moving")

        def step():
            self.step(axis, delta)

        return self.poll(names, duration_s, rate_Hz, at=[(pre_s, step)])

    def frf(self, axis, frequencies_Hz: Sequence[float], amplitude: float, cycles: int = 6,
            settle_cycles: int = 2, rate_Hz: float = 400.0,
            progress: Optional[Callable[[int, int, float], None]] = None) -> FrfResult:
        """HOST-DRIVEN stepped-sine FRF of the closed loop, reference -> measured position,
        on ``axis``: for each frequency the host writes reference steps so that the
        reference follows amplitude*sin(2 pi f t) as a staircase updated at the poll rate,
        reads the pose between updates, and fits sines to both (after ``settle_cycles``).
        The reference staircase is assigned to the middle of each hold interval (its
        zero-order hold), so the phase is right to about the link's jitter: keep
        f well below rate_Hz / 10. The reference returns to its start between frequencies.
        ``progress(index, count, f_Hz)`` is called before each frequency of the sweep."""
        ax = _axis_index(axis)
        pose_name = POSE_REGISTERS[AXES[ax]]
        result_f, result_h, result_c = [], [], []
        frequencies_Hz = list(frequencies_Hz)
        for index, f in enumerate(frequencies_Hz):
            if progress is not None:
                progress(index, len(frequencies_Hz), f)
            total_s = (settle_cycles + cycles) / f
            applied = 0.0
            t_cmd: List[float] = []
            r_cmd: List[float] = []
            t_y: List[float] = []
            y: List[float] = []
            t0 = time.monotonic()
            next_t = t0
            while True:
                now = time.monotonic() - t0
                if now >= total_s:
                    break
                want = amplitude * math.sin(2.0 * math.pi * f * now)
                self.command("step", ax, want - applied)
                t_cmd.append(time.monotonic() - t0)
                applied = want
                r_cmd.append(applied)
                ta = time.monotonic()
                value = self.read(pose_name)
                t_y.append((ta + time.monotonic()) / 2 - t0)
                y.append(value)
                next_t += 1.0 / rate_Hz
                sleep = next_t - time.monotonic()
                if sleep > 0:
                    time.sleep(sleep)
                else:
                    next_t = time.monotonic()
            self.command("step", ax, -applied)
            t_cmd_a, r_a, t_y_a, y_a = map(np.asarray, (t_cmd, r_cmd, t_y, y))
            # Zero-order hold: value r_k holds from t_k to t_k+1; its centre is the midpoint.
            t_ref = np.append((t_cmd_a[:-1] + t_cmd_a[1:]) / 2, t_cmd_a[-1])
            keep_r = t_ref >= settle_cycles / f
            keep_y = t_y_a >= settle_cycles / f
            r_amp, _ = sine_fit(t_ref[keep_r], r_a[keep_r], f)
            y_amp, y_fit_residual = sine_fit(t_y_a[keep_y], y_a[keep_y], f)
            h = y_amp / r_amp
            # Fraction of the (de-meaned) response power the fitted sine explains.
            y_var = float(np.var(y_a[keep_y]))
            coherence = 1.0 - y_fit_residual / y_var if y_var > 0 else 0.0
            result_f.append(f)
            result_h.append(h)
            result_c.append(coherence)
            time.sleep(0.05)
        return FrfResult(np.array(result_f), np.array(result_h), np.array(result_c))

    # ---- the on-board recorder (docs/LAB-TOOLS.md) -------------------------------
    _TRIGGER_MODES = {"immediate": 0, "command": 1, "level": 2, "fault": 3}
    _EDGES = {"rising": 0, "falling": 1, "either": 2}

    def record(self, signals: Sequence[str] = ("x.pose", "x.reference", "x.error", "x.effort"),
               duration_s: float = 1.0, decimation: int = 1, trigger: str = "immediate",
               pretrigger_s: float = 0.0, level: Optional[Tuple[str, float, str]] = None,
               timeout_s: float = 30.0, during: Optional[Callable[[], None]] = None,
               progress: Optional[Callable[[str, int, int], None]] = None) -> Recording:
        """Record ``signals`` (LAB_SIGNALS names) with the controller's own recorder, in
        the servo loop (no link jitter), and download them. The recorder is stopped,
        configured and armed in one request; ``during()`` (e.g. a step command) runs once
        the pre-trigger samples are in;
        then it waits for the capture (rec.state 3) and reads it block by block (0x17:
        rec.read_offset + rec.data). ``trigger``: immediate | command | fault | level,
        with ``level = (signal, value, "rising"|"falling"|"either")``. Recording.t is 0
        at the trigger sample. ``progress(phase, done, total)``: "waiting" (state),
        "download" (values)."""
        try:
            ids = [LAB_SIGNALS[n].id for n in signals]
        except KeyError as e:
            raise errors.ValueOutOfRange(f"unknown signal {e.args[0]!r} (maglev.LAB_SIGNALS lists them)") from None
        if trigger not in self._TRIGGER_MODES:
            raise errors.ValueOutOfRange(f"trigger {trigger!r}: one of {', '.join(self._TRIGGER_MODES)}")
        self.write("rec.control", 3)  # stop (configuration is refused, 06, while armed)
        # The servo rate: rec.sample_rate is it over the present decimation.
        tick_Hz = self.read("rec.sample_rate") * self.read("rec.decimation")
        length = max(2, int(round(duration_s * tick_Hz / decimation)))
        pre = int(round(pretrigger_s * tick_Hz / decimation))
        config = {"rec.control": 1, "rec.channel_count": len(ids), "rec.decimation": decimation,
                  "rec.length": length, "rec.pretrigger": pre, "rec.trigger_mode": self._TRIGGER_MODES[trigger],
                  "rec.trigger_signal": 1, "rec.trigger_edge": 0, "rec.trigger_level": 0.0}
        for k in range(8):
            config[f"rec.channel.{k}"] = ids[k] if k < len(ids) else ids[0]
        if trigger == "level":
            if level is None:
                raise errors.ValueOutOfRange("a level trigger needs level=(signal, value, edge)")
            config.update({"rec.trigger_signal": LAB_SIGNALS[level[0]].id, "rec.trigger_level": level[1],
                           "rec.trigger_edge": self._EDGES[level[2]]})
        # One 0x10 over rec.control .. rec.trigger_level: the firmware checks the
        # whole configuration at once and applies rec.control (arm) after it.
        self.write_block(config)
        if during is not None:
            # Let the pre-trigger samples fill first (the recorder keeps only what
            # it saw since it was armed).
            time.sleep(pre / (tick_Hz / decimation) + 0.01)
            during()
        t0 = time.monotonic()
        last = None
        while True:
            state = self.read("rec.state")
            if progress is not None and state != last:
                progress("waiting", state, 3)
            last = state
            if state == 3:
                break
            if time.monotonic() - t0 > timeout_s:
                raise errors.WaitTimeout(f"recorder state {state} after {timeout_s:g} s (3 = done)")
            time.sleep(0.02)
        v = self.read_many(("rec.captured", "rec.trigger_index", "rec.sample_rate", "rec.capture_id"))
        n_ch = len(ids)
        total = int(v["rec.captured"]) * n_ch
        offset_reg, data_reg = register("rec.read_offset"), register("rec.data")
        per_block = data_reg.width // 2
        values = np.empty(total, dtype=np.float32)
        for k in range(0, total, per_block):
            words = self._write_read(offset_reg.address, offset_reg.encode(k), data_reg.address, data_reg.width,
                                     "rec.data")
            block = np.frombuffer(np.array(words, dtype=">u2").tobytes(), dtype=">f4")
            n = min(per_block, total - k)
            values[k:k + n] = block[:n]
            if progress is not None:
                progress("download", k + n, total)
        if self.read("rec.capture_id") != v["rec.capture_id"]:
            raise errors.CommunicationError("the capture changed during the download (re-armed by another client)")
        samples = values.reshape(-1, n_ch).astype(float)
        t = (np.arange(samples.shape[0]) - v["rec.trigger_index"]) / v["rec.sample_rate"]
        return Recording(t, {name: samples[:, i] for i, name in enumerate(signals)})

    def frf_onboard(self, axis, amplitude_A: float = 0.1, f_min_Hz: float = 5.0, f_max_Hz: float = 400.0,
                    tones: int = 28, periods: int = 4, settle_s: float = 1.0,
                    progress: Optional[Callable[[str, int, int], None]] = None) -> FrfResult:
        """OPEN-LOOP FRF of ``axis`` measured on board, what `stagectl frf` measures
        (docs/LAB-TOOLS.md): the wave generator injects a multisine (``tones`` lines on
        the 1 Hz grid, f_min..f_max, ``amplitude_A`` peak) at the axis' effort, the
        recorder takes d (excitation), u (loop effort) and u + d at the servo rate over
        ``periods`` 1-s periods after ``settle_s``; L = -u / (u + d) at the tones, H1
        over the periods, and its coherence. Needs the stage Ready."""
        name = AXES[_axis_index(axis)]
        self.write("wave.control", 2)
        self.write_block({"wave.control": 1, "wave.axis": _axis_index(axis), "wave.point": 0, "wave.shape": 2,
                          "wave.tones": tones, "wave.amplitude": amplitude_A, "wave.f_start": f_min_Hz,
                          "wave.f_end": f_max_Hz, "wave.duration": 0.0})
        try:
            time.sleep(settle_s)
            rec = self.record([f"{name}.excitation", f"{name}.loop_effort", f"{name}.effort"],
                              duration_s=float(periods), timeout_s=30.0 + periods, progress=progress)
            running = self.read("wave.state") == 1
        finally:
            self.write("wave.control", 2)
        if not running:
            raise errors.CommandRejected("frf_onboard", "the wave generator stopped during the measurement")
        fs = 1.0 / float(np.median(np.diff(rec.t)))
        period = int(round(fs))  # 1-s periods: the multisine's lines sit on its 1 Hz grid
        d = rec[f"{name}.excitation"]
        u = -rec[f"{name}.loop_effort"]  # L = -u / (u + d)
        e = rec[f"{name}.effort"]
        n = (len(d) // period) * period
        D = np.fft.rfft(d[:n].reshape(-1, period), axis=1)
        U = np.fft.rfft(u[:n].reshape(-1, period), axis=1)
        E = np.fft.rfft(e[:n].reshape(-1, period), axis=1)
        mag = np.abs(D[0])
        lines = np.nonzero(mag > 0.05 * mag[1:].max())[0]
        lines = lines[lines > 0]
        s_ue = (U[:, lines] * np.conj(E[:, lines])).sum(axis=0)
        s_ee = (np.abs(E[:, lines]) ** 2).sum(axis=0)
        s_uu = (np.abs(U[:, lines]) ** 2).sum(axis=0)
        return FrfResult(lines * fs / period, s_ue / s_ee, np.abs(s_ue) ** 2 / (s_uu * s_ee))
