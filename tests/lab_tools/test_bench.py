"""maglev package against `maglev-hil serve` (MAGLEV_TCP=HOST:PORT, set by with_serve.sh).

Classes run in name order: Test1Landed (bad input, commands refused while
landed), Test2Levitated (levitate with progress, busy writes, move, step
response, FRF, a calibration interrupted, land).
"""
import os
import time
import unittest

import numpy as np

import maglev

HOST, PORT = os.environ["MAGLEV_TCP"].rsplit(":", 1)


def connect():
    return maglev.Stage.tcp(HOST, int(PORT))


class Test1Landed(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.stage = connect()

    @classmethod
    def tearDownClass(cls):
        cls.stage.close()

    def test_identity(self):
        s = self.stage
        self.assertEqual(s.read("id.magic"), 0x4D4C)
        self.assertEqual(s.read("id.schema_hash") & 0xFFFFFFFF, maglev.SCHEMA_HASH)
        self.assertEqual(s.state(), maglev.SequencerState.IDLE)

    def test_read_many_matches_single_reads(self):
        s = self.stage
        names = ["max_velocity.x", "gain.z.kp", "limit.x_max", "status.state", "seq.nominal_height"]
        many = s.read_many(names)
        self.assertEqual(list(many), names)
        for n in names:
            self.assertEqual(many[n], s.read(n))
        self.assertAlmostEqual(many["gain.z.kp"], maglev.register("gain.z.kp").default, delta=1e-3)

    def test_write_and_read_back(self):
        s = self.stage
        s.write("max_velocity.x", 0.01)
        self.assertAlmostEqual(s.read("max_velocity.x"), 0.01, delta=1e-9)
        s.write("max_velocity.x", maglev.register("max_velocity.x").default)

    def test_local_range_check_sends_nothing(self):
        s = self.stage
        before = s.read("max_velocity.x")
        with self.assertRaises(maglev.ValueOutOfRange):
            s.write("max_velocity.x", 5.0)  # max 1 m/s
        with self.assertRaises(maglev.ValueOutOfRange):
            s.write("status.x", 0.0)  # read-only
        with self.assertRaises(maglev.UnknownRegister):
            s.read("status.w")
        self.assertEqual(s.read("max_velocity.x"), before)

    def test_exception_01_engineer_register_without_key(self):
        with self.assertRaises(maglev.IllegalFunction) as cm:
            self.stage.write("gain.x.kp", 1000.0)
        self.assertEqual(cm.exception.code, 0x01)
        self.assertEqual(cm.exception.register, "gain.x.kp")

    def test_engineer_context_unlocks_and_relocks(self):
        s = self.stage
        kp = s.read("gain.x.kp")
        with s.engineer():
            self.assertEqual(s.read("access.level"), 2)
            s.write("gain.x.kp", kp)  # same value: accepted
        self.assertEqual(s.read("access.level"), 1)

    def test_exception_02_unmapped_address(self):
        with self.assertRaises(maglev.IllegalDataAddress):
            self.stage.read_words(5000, 1)
        with self.assertRaises(maglev.IllegalDataAddress):  # read-only register, raw write
            self.stage.write_words(maglev.register("status.state").address, [1])

    def test_exception_03_value_refused_and_nothing_changed(self):
        s = self.stage
        r = maglev.register("max_velocity.x")
        before = s.read(r.name)
        with self.assertRaises(maglev.IllegalDataValue):
            s.write_words(r.address, r.encode(5.0))  # past the local check: the server refuses
        self.assertEqual(s.read(r.name), before)

    def test_command_rejected_while_landed(self):
        with self.assertRaises(maglev.CommandRejected) as cm:
            self.stage.step("x", 1e-6)
        self.assertEqual(cm.exception.result, maglev.CommandResult.REFUSED_NOT_READY)
        with self.assertRaises(maglev.ValueOutOfRange):
            self.stage.command("step", "w", 1e-6)

    def test_calibration_refused_while_landed(self):
        s = self.stage
        with self.assertRaises(maglev.CommandRejected) as cm:
            s.calibrate_coupling()
        self.assertEqual(cm.exception.result, maglev.CommandResult.REFUSED_NOT_READY)
        self.assertEqual(maglev.CouplingCalibrationResult(int(s.read("status.calibration"))),
                         maglev.CouplingCalibrationResult.REFUSED_NOT_READY)

    def test_home_waits_with_progress(self):
        seen = []
        self.stage.home(timeout_s=20, progress=lambda st, t: seen.append(st))
        self.assertEqual(self.stage.state(), maglev.SequencerState.IDLE)
        self.assertEqual(seen[-1], maglev.SequencerState.IDLE)
        self.assertEqual(self.stage.read("status.moving"), 0)

    def test_poll_returns_arrays(self):
        rec = self.stage.poll(("status.x", "status.z", "status.state"), duration_s=0.3, rate_Hz=200)
        self.assertGreater(len(rec), 30)  # 60 asked for; a loaded CI machine may lose some
        self.assertLessEqual(len(rec), 62)
        self.assertEqual(rec["status.x"].shape, rec.t.shape)
        self.assertTrue(np.all(np.diff(rec.t) > 0))
        self.assertTrue(np.all(rec["status.state"] == 0))


class Test2Levitated(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.stage = connect()
        cls.progress = []
        cls.stage.levitate(timeout_s=30, progress=lambda st, t: cls.progress.append((st, t)))

    @classmethod
    def tearDownClass(cls):
        cls.stage.close()

    def test_a_levitate_progress_went_through_the_sequence(self):
        states = [st for st, _ in self.progress]
        self.assertEqual(states[-1], maglev.SequencerState.READY)
        self.assertIn(maglev.SequencerState.LIFT, states)
        self.assertAlmostEqual(self.stage.read("status.z"), self.stage.read("seq.nominal_height"), delta=1e-6)

    def test_b_exception_06_landed_only_write_while_levitated(self):
        s = self.stage
        before = s.read("max_velocity.x")
        with self.assertRaises(maglev.ServerDeviceBusy) as cm:
            s.write("max_velocity.x", 0.01)
        self.assertEqual(cm.exception.code, 0x06)
        self.assertEqual(s.read("max_velocity.x"), before)

    def test_c_move_by(self):
        s = self.stage
        x0 = s.read("status.x")
        s.move_by("x", 1e-3, timeout_s=10)
        time.sleep(0.2)
        self.assertAlmostEqual(s.read("status.x") - x0, 1e-3, delta=1e-6)

    def test_d_step_response(self):
        s = self.stage
        delta = 10e-6
        rec = s.step_response("x", delta, duration_s=0.4, pre_s=0.05, rate_Hz=500)
        t_step = rec.events[0][0]
        x = rec["status.x"]
        before = x[rec.t < t_step]
        after = x[rec.t > t_step + 0.25]
        self.assertGreater(len(before), 5)
        self.assertGreater(len(after), 5)
        self.assertAlmostEqual(after.mean() - before.mean(), delta, delta=0.5e-6)

    def test_e_frf_low_frequency_is_unity(self):
        seen = []
        r = self.stage.frf("x", [3.0], amplitude=2e-6, cycles=3, settle_cycles=1, rate_Hz=300,
                           progress=lambda i, n, f: seen.append((i, n, f)))
        self.assertEqual(seen, [(0, 1, 3.0)])
        self.assertEqual(r.f_Hz.tolist(), [3.0])
        self.assertAlmostEqual(abs(r.h[0]), 1.0, delta=0.15)
        self.assertLess(abs(r.phase_deg[0]), 30.0)
        self.assertGreater(r.coherence[0], 0.9)

    def test_f_record_on_board(self):
        # The controller's recorder: a level trigger on the x reference catches a
        # 2 um step with 50 ms of pre-trigger, at the servo rate.
        s = self.stage
        x0 = s.read("status.x")
        phases = []
        rec = s.record(["x.pose", "x.reference", "x.effort"], duration_s=0.3, pretrigger_s=0.05,
                       trigger="level", level=("x.reference", x0 + 1e-6, "rising"),
                       during=lambda: s.step("x", 2e-6), progress=lambda p, d, n: phases.append(p))
        self.assertEqual(rec.names, ("x.pose", "x.reference", "x.effort"))
        self.assertEqual(len(rec), 750)  # 0.3 s at 2.5 kHz
        self.assertAlmostEqual(float(np.median(np.diff(rec.t))), 1 / 2500.0, delta=1e-9)
        self.assertAlmostEqual(rec.t[0], -0.05, delta=0.002)  # the pre-trigger samples are there
        r = rec["x.reference"]
        self.assertAlmostEqual(r[rec.t > 0].mean() - r[rec.t < 0].mean(), 2e-6, delta=1e-9)
        x = rec["x.pose"]
        self.assertAlmostEqual(x[rec.t > 0.2].mean() - x[rec.t < 0].mean(), 2e-6, delta=0.05e-6)
        self.assertIn("download", phases)
        with self.assertRaises(maglev.ValueOutOfRange):
            s.record(["x.nope"])

    def test_g_frf_on_board_matches_stagectl(self):
        # The open loop of x from the wave generator + recorder: crossover and phase
        # margin as `stagectl frf x` measures them on the same bench (PERFORMANCE.md:
        # 50.47 Hz, 28.2 deg over three runs).
        # 0.2 A, not the default 0.1 A: at 5 Hz the loop gain is large, e = u + d is
        # small and the line's coherence sat at 0.91 (idle machine) to 0.79 (both cores
        # busy: CI's parallel tests), against the 0.9 gate; at 0.2 A it is 0.98 / 0.96.
        r = self.stage.frf_onboard("x", amplitude_A=0.2)
        self.assertGreater(len(r.f_Hz), 20)
        self.assertTrue(np.all(r.coherence > 0.9),
                        f"coherence {np.round(r.coherence, 3).tolist()} at {np.round(r.f_Hz, 1).tolist()} Hz")
        mag = r.magnitude_dB
        k = int(np.nonzero((mag[:-1] > 0) & (mag[1:] <= 0))[0][0])
        a = mag[k] / (mag[k] - mag[k + 1])  # linear in dB over log f
        f_c = float(np.exp(np.log(r.f_Hz[k]) + a * (np.log(r.f_Hz[k + 1]) - np.log(r.f_Hz[k]))))
        phase = float(r.phase_deg[k] + a * (r.phase_deg[k + 1] - r.phase_deg[k]))
        self.assertAlmostEqual(f_c, 50.47, delta=1.5)
        self.assertAlmostEqual(180.0 + phase, 28.2, delta=2.0)
        self.assertEqual(self.stage.read("wave.state") in (0, 2), True)  # stopped again

    def test_h_calibration_interrupted_by_hold_keeps_nothing(self):
        # The full ~28 s run is tests/hil/fidelity/serve_calibration.sh (stagectl, as-built);
        # here the package's side of one that another command interrupts.
        s = self.stage
        R = maglev.CouplingCalibrationResult
        self.assertIsNone(s.calibrate_coupling(wait=False))
        t0 = time.monotonic()
        while R(int(s.read("status.calibration"))) != R.RUNNING:
            self.assertLess(time.monotonic() - t0, 2.0, "the calibration never ran")
            time.sleep(0.01)
        s.hold()
        while R(int(s.read("status.calibration"))) == R.RUNNING:
            self.assertLess(time.monotonic() - t0, 4.0, "hold did not end the calibration")
            time.sleep(0.01)
        self.assertEqual(R(int(s.read("status.calibration"))), R.ABANDONED_INTERRUPTED)
        self.assertEqual(s.read("coupling.enabled"), 0)
        self.assertEqual(s.state(), maglev.SequencerState.READY)

    def test_z_land(self):
        self.stage.land(timeout_s=30)
        self.assertEqual(self.stage.state(), maglev.SequencerState.IDLE)


if __name__ == "__main__":
    unittest.main()
