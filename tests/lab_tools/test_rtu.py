"""maglev package over Modbus RTU: the firmware's RtuServer (and the real kernel)
behind a pseudo-terminal (MAGLEV_RTU=PATH, set by with_rtu_serve.sh)."""
import os
import time
import unittest

import maglev


class RtuTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.stage = maglev.Stage.rtu(os.environ["MAGLEV_RTU"], 115200)

    @classmethod
    def tearDownClass(cls):
        cls.stage.close()

    def test_identity_and_status(self):
        self.assertEqual(self.stage.read("id.magic"), 0x4D4C)
        self.assertEqual(self.stage.read("id.schema_hash") & 0xFFFFFFFF, maglev.SCHEMA_HASH)
        self.assertEqual(self.stage.status()["status.state"], maglev.SequencerState.IDLE)

    def test_write_read_back(self):
        s = self.stage
        s.write("max_velocity.y", 0.02)
        self.assertAlmostEqual(s.read("max_velocity.y"), 0.02, delta=1e-9)
        s.write("max_velocity.y", maglev.register("max_velocity.y").default)

    def test_exceptions_over_rtu(self):
        s = self.stage
        with self.assertRaises(maglev.IllegalFunction):
            s.write("gain.y.kp", 1000.0)
        with self.assertRaises(maglev.IllegalDataAddress):
            s.read_words(5000, 1)
        r = maglev.register("max_velocity.y")
        with self.assertRaises(maglev.IllegalDataValue):
            s.write_words(r.address, r.encode(5.0))

    def test_command_reaches_the_unit(self):
        # 0x17 to unit 1 (pymodbus 3.0's readwrite_registers() would send it to
        # unit 0, a broadcast no server answers): the kernel's result comes back.
        with self.assertRaises(maglev.CommandRejected) as cm:
            self.stage.step("x", 1e-6)
        self.assertEqual(cm.exception.result, maglev.CommandResult.REFUSED_NOT_READY)
        self.assertEqual(self.stage.command("hold"), maglev.CommandResult.ACCEPTED)

    def test_poll(self):
        t0 = time.monotonic()
        rec = self.stage.poll(("status.x", "status.z"), duration_s=0.3, rate_Hz=100)
        self.assertGreater(len(rec), 10)
        self.assertLess(time.monotonic() - t0, 2.0)


if __name__ == "__main__":
    unittest.main()
