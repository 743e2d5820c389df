"""Exceptions of the maglev package.

Every Modbus exception code a server may answer has its own class
(ModbusExceptionError.code); the maglev controller answers 01, 02, 03, 04
and 06 (firmware/modbus register_server.hpp ExceptionCode), the others are
defined by the Modbus application protocol (05, 08, 0A, 0B) and raised the
same way should a gateway or another server send them.
"""


class MaglevError(Exception):
    """Base of every error this package raises."""


class UnknownRegister(MaglevError, KeyError):
    """No register of that name in registers.def (maglev.REGISTERS lists them)."""

    def __str__(self):
        return f"unknown register {self.args[0]!r} (maglev.REGISTERS lists them)"


class ValueOutOfRange(MaglevError, ValueError):
    """Checked locally before anything is sent: the value is outside the register's [min, max],
    not finite, not an integer for an integer register, or the register is read-only."""


class CommunicationError(MaglevError):
    """No answer, a broken connection, or a malformed reply (nothing known about the write)."""


class ModbusExceptionError(MaglevError):
    """The controller answered a Modbus exception: nothing was changed."""

    code = None  # the exception code, set by each subclass
    meaning = ""

    def __init__(self, register=None, function=None, detail=""):
        self.register = register
        self.function = function
        where = f" on {register}" if register else ""
        fc = f" (function 0x{function:02X})" if function is not None else ""
        super().__init__(f"Modbus exception {self.code:02X} {self.meaning}{where}{fc}{': ' + detail if detail else ''}")


class IllegalFunction(ModbusExceptionError):
    code, meaning = 0x01, "illegal function (or engineer access required: write the engineer key first)"


class IllegalDataAddress(ModbusExceptionError):
    code, meaning = 0x02, "illegal data address (not in the map, read-only, or splits a 32-bit value)"


class IllegalDataValue(ModbusExceptionError):
    code, meaning = 0x03, "illegal data value (out of range, or the controller refused the configuration)"


class ServerDeviceFailure(ModbusExceptionError):
    code, meaning = 0x04, "server device failure (e.g. the flash save did not verify)"


class Acknowledge(ModbusExceptionError):
    code, meaning = 0x05, "acknowledge (long operation accepted, poll for completion)"


class ServerDeviceBusy(ModbusExceptionError):
    code, meaning = 0x06, "server device busy (not writable in the present state)"


class MemoryParityError(ModbusExceptionError):
    code, meaning = 0x08, "memory parity error"


class GatewayPathUnavailable(ModbusExceptionError):
    code, meaning = 0x0A, "gateway path unavailable"


class GatewayTargetFailedToRespond(ModbusExceptionError):
    code, meaning = 0x0B, "gateway target device failed to respond"


class UnknownModbusException(ModbusExceptionError):
    """A code outside the protocol's list; .code holds it."""

    meaning = "unknown exception code"

    def __init__(self, code, register=None, function=None, detail=""):
        self.code = code
        super().__init__(register, function, detail)


MODBUS_EXCEPTIONS = {
    cls.code: cls
    for cls in (IllegalFunction, IllegalDataAddress, IllegalDataValue, ServerDeviceFailure, Acknowledge,
                ServerDeviceBusy, MemoryParityError, GatewayPathUnavailable, GatewayTargetFailedToRespond)
}


def modbus_exception(code, register=None, function=None, detail=""):
    """The exception object for Modbus exception ``code``."""
    cls = MODBUS_EXCEPTIONS.get(code)
    if cls is None:
        return UnknownModbusException(code, register, function, detail)
    return cls(register, function, detail)


class CommandRejected(MaglevError):
    """The kernel refused a host command: cmd.result != 0 (.result is a maglev.CommandResult)."""

    def __init__(self, command, result):
        self.command = command
        self.result = result
        super().__init__(f"{command} rejected: {result.text if hasattr(result, 'text') else result}")


class StageFaulted(MaglevError):
    """While waiting, the stage latched a fault (.fault is a maglev.FaultCode)."""

    def __init__(self, fault, waiting_for):
        self.fault = fault
        super().__init__(f"stage faulted ({getattr(fault, 'name', fault)}) while waiting for {waiting_for}")


class WaitTimeout(MaglevError, TimeoutError):
    """The stage did not get there in time."""


class CalibrationFailed(MaglevError):
    """The kernel's coupling calibration ended without storing a correction: refused once
    running, abandoned (a fault, another command) or a failed check; the previous correction
    stays. ``.result`` is the CalibrationResult (its ``.result`` a maglev.CouplingCalibrationResult,
    with the couplings found)."""

    def __init__(self, result):
        self.result = result
        super().__init__(f"coupling calibration {result.result.name} (docs/KERNEL.md): "
                         f"the previous correction stays (coupling found {result.coupling_before:g}, "
                         f"after {result.coupling_after:g})")
