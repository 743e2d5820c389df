"""maglev package without a server: tables, encodings, exception classes."""
import struct
import unittest

import maglev
from maglev import errors
from maglev.client import _blocks


class TablesTest(unittest.TestCase):
    def test_registers_sorted_and_disjoint(self):
        regs = list(maglev.REGISTERS.values())
        self.assertGreater(len(regs), 100)
        for a, b in zip(regs, regs[1:]):
            self.assertLessEqual(a.address + a.width, b.address, (a.name, b.name))

    def test_known_entries(self):
        r = maglev.register("status.x")
        self.assertEqual((r.address, r.type, r.unit, r.access), (104, "f32", "m", "read-only"))
        self.assertEqual(maglev.register("id.magic").default, 0x4D4C)
        self.assertEqual(maglev.register("cmd.code").address, maglev.register("cmd.axis").address + 3)

    def test_commands_and_enums(self):
        self.assertEqual(maglev.HOST_COMMANDS["levitate"].code, 2)
        self.assertEqual([f.name for f in maglev.HOST_COMMANDS["move_to"].fields],
                         ["target", "velocity", "acceleration"])
        self.assertEqual(maglev.SequencerState.READY, 6)
        self.assertEqual(maglev.SequencerState(3).text, "Lift")
        self.assertEqual(maglev.FaultCode.FOLLOWING_ERROR, 6)
        self.assertEqual(maglev.CommandResult.REFUSED_NOT_READY.text, "refused: not ready")
        self.assertEqual(maglev.AXES, ("x", "y", "theta_z", "z", "theta_x", "theta_y"))

    def test_unknown_register(self):
        with self.assertRaises(maglev.UnknownRegister):
            maglev.register("status.w")
        with self.assertRaises(KeyError):  # it is also a KeyError
            maglev.register("nope")


class EncodingTest(unittest.TestCase):
    def test_f32_abcd(self):
        words = maglev.register("status.x").encode(1.5e-3)
        raw = struct.pack(">f", 1.5e-3)
        self.assertEqual(words, (int.from_bytes(raw[:2], "big"), int.from_bytes(raw[2:], "big")))
        self.assertAlmostEqual(maglev.register("status.x").decode(words), 1.5e-3, delta=1e-10)

    def test_i32_signed(self):
        r = maglev.register("id.schema_hash")
        self.assertEqual(r.decode(r.encode(-5)), -5)
        self.assertEqual(r.encode(-1), (0xFFFF, 0xFFFF))

    def test_range_check(self):
        r = maglev.register("cmd.axis")
        self.assertTrue(r.in_range(5))
        self.assertFalse(r.in_range(6))
        self.assertFalse(r.in_range(1.5))
        self.assertFalse(maglev.register("cmd.value").in_range(float("nan")))

    def test_blocks_are_mapped_and_short(self):
        regs = list(maglev.REGISTERS.values())
        for run in _blocks(regs):
            span = run[-1].address + run[-1].width - run[0].address
            self.assertLessEqual(span, 125)
            mapped = {a for r in regs for a in range(r.address, r.address + r.width)}
            for a in range(run[0].address, run[-1].address + run[-1].width):
                self.assertIn(a, mapped)  # no unmapped address inside a read
        self.assertEqual(len(_blocks([maglev.register(n) for n in maglev.STATUS_NAMES])), 1)


class ExceptionsTest(unittest.TestCase):
    def test_every_protocol_code_has_a_named_class(self):
        expected = {0x01: "IllegalFunction", 0x02: "IllegalDataAddress", 0x03: "IllegalDataValue",
                    0x04: "ServerDeviceFailure", 0x05: "Acknowledge", 0x06: "ServerDeviceBusy",
                    0x08: "MemoryParityError", 0x0A: "GatewayPathUnavailable",
                    0x0B: "GatewayTargetFailedToRespond"}
        for code, name in expected.items():
            e = errors.modbus_exception(code, "status.x", 0x03)
            self.assertEqual(type(e).__name__, name)
            self.assertEqual(e.code, code)
            self.assertIsInstance(e, maglev.ModbusExceptionError)
            self.assertIsInstance(e, maglev.MaglevError)
            self.assertIn(f"{code:02X}", str(e))
            self.assertIs(getattr(maglev, name), type(e))
        odd = errors.modbus_exception(0x42)
        self.assertIsInstance(odd, maglev.UnknownModbusException)
        self.assertEqual(odd.code, 0x42)


if __name__ == "__main__":
    unittest.main()
