"""Typed view of the firmware tables in ``_tables.py`` (generated, never edited).

Every name here comes from the firmware's one definition: registers from
registers.def, host commands from can_link's kHostCommandSpecs, axes from
kAxisNames, states/faults/results from the MAGLEV_* X-macro lists.
"""
import enum
import math
import struct
from dataclasses import dataclass
from typing import Dict, Tuple

from . import _tables


@dataclass(frozen=True)
class Register:
    """One entry of registers.def (see docs/REGISTERS.md)."""

    name: str
    address: int
    type: str  # "u16" | "i32" | "f32" | "block"; i32/f32 span two registers, ABCD word order;
    # a block is a download window of BLOCK_WORDS registers (the recorder's data)
    unit: str
    min: float
    max: float
    default: float
    access: str  # "read-only" | "operator" | "engineer"
    writable_when: str  # "never" | "always" | "not-moving" | "idle" | "gains"
    persisted: bool
    kind: str  # "ident" | "status" | "config" | "control" | "stage" | "lab"
    description: str

    @property
    def width(self) -> int:
        """Number of 16-bit Modbus registers the value occupies."""
        return {"u16": 1, "block": _tables.BLOCK_WORDS}.get(self.type, 2)

    def encode(self, value: float) -> Tuple[int, ...]:
        """The register words of ``value`` (big-endian words: high half first)."""
        if self.type == "block":
            raise ValueError(f"{self.name} is a read-only download window")
        if self.type == "u16":
            return (int(value) & 0xFFFF,)
        raw = struct.pack(">i", int(value)) if self.type == "i32" else struct.pack(">f", float(value))
        return struct.unpack(">HH", raw)

    def decode(self, words) -> float:
        """The value carried by ``words`` (int for u16/i32, float for f32, the
        words themselves for a block)."""
        if self.type == "block":
            return list(words)
        if self.type == "u16":
            return int(words[0])
        raw = struct.pack(">HH", int(words[0]), int(words[1]))
        return struct.unpack(">i" if self.type == "i32" else ">f", raw)[0]

    def in_range(self, value: float) -> bool:
        """The firmware's value_in_range(): finite, inside [min, max], integral for u16/i32."""
        if not math.isfinite(value) or value < self.min or value > self.max:
            return False
        return self.type == "f32" or float(value).is_integer()


REGISTERS: Dict[str, Register] = {row[0]: Register(*row) for row in _tables.REGISTERS}
"""Every register by name, in address order."""

SCHEMA_HASH: int = _tables.SCHEMA_HASH
ENGINEER_KEY: int = _tables.ENGINEER_KEY
PERSIST_FLAGS: Dict[str, int] = dict(_tables.PERSIST_FLAGS)

AXES: Tuple[str, ...] = tuple(name for name, _ in _tables.AXES)
"""Axis names in kernel Axis order (the value of cmd.axis)."""
ROTATIONAL_AXES = frozenset(name for name, rotational in _tables.AXES if rotational)

# status.<axis> register of each axis' measured pose.
POSE_REGISTERS: Dict[str, str] = {axis: "status." + axis for axis in AXES}


@dataclass(frozen=True)
class LabSignal:
    """A signal the on-board recorder can record (lab_tools signals.hpp; ids pinned)."""

    id: int
    name: str  # "x.pose", "coil3.current", "state"
    unit: str
    description: str


LAB_SIGNALS: Dict[str, LabSignal] = {row[1]: LabSignal(*row) for row in _tables.LAB_SIGNALS}


@dataclass(frozen=True)
class CommandField:
    name: str
    quantity: str
    range: str
    comment: str


@dataclass(frozen=True)
class HostCommand:
    """One entry of kHostCommandSpecs (its code is the cmd.code value)."""

    code: int
    name: str
    takes_axis: bool
    fields: Tuple[CommandField, ...]
    comment: str


HOST_COMMANDS: Dict[str, HostCommand] = {
    name: HostCommand(code, name, takes_axis, tuple(CommandField(*f) for f in fields), comment)
    for code, name, takes_axis, fields, comment in _tables.HOST_COMMANDS
}


def _enum(name: str, rows) -> type:
    # k-prefixed C++ enumerators -> Python names: kZLock -> Z_LOCK.
    def py_name(enumerator: str) -> str:
        out = ""
        body = enumerator[1:]
        for i, ch in enumerate(body):
            if ch.isupper() and i > 0 and (not body[i - 1].isupper() or (i + 1 < len(body) and body[i + 1].islower())):
                out += "_"
            out += ch.upper()
        return out

    cls = enum.IntEnum(name, [(py_name(e), value) for value, e, _ in rows])
    texts = {value: text for value, _, text in rows}
    cls.text = property(lambda self: texts[int(self)])
    return cls


SequencerState = _enum("SequencerState", _tables.SEQUENCER_STATES)
TransitionReason = _enum("TransitionReason", _tables.TRANSITION_REASONS)
FaultCode = _enum("FaultCode", _tables.FAULT_CODES)
CommandResult = _enum("CommandResult", _tables.COMMAND_RESULTS)
ConfigError = _enum("ConfigError", _tables.CONFIG_ERRORS)
ProfileError = _enum("ProfileError", _tables.PROFILE_ERRORS)
CouplingCalibrationResult = _enum("CouplingCalibrationResult", _tables.COUPLING_CALIBRATION_RESULTS)


def register(name: str) -> Register:
    """The register called ``name``; UnknownRegister (a KeyError) otherwise."""
    from .errors import UnknownRegister

    try:
        return REGISTERS[name]
    except KeyError:
        raise UnknownRegister(name) from None


def state_name(value: int) -> str:
    try:
        return SequencerState(value).text
    except ValueError:
        return "?"
