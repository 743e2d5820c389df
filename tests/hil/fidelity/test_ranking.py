"""hil/report/ranking.py: when the comparison scripts call two controllers' figures different.

usage: test_ranking.py HIL_REPORT_DIR
"""
import os
import sys
import unittest

sys.dont_write_bytecode = True  # a test never writes into the source tree
sys.path.insert(0, sys.argv.pop(1))
import ranking  # noqa: E402
import preset_comparison  # noqa: E402


class Ranking(unittest.TestCase):
    def test_ccq_keys_and_their_rest_noise_keys(self):
        self.assertTrue(ranking.is_ccq("theta_z_step1_ccq_x_m_s_per_rad"))
        self.assertFalse(ranking.is_ccq("theta_z_step1_ccq_rest_noise_x_m_s_per_rad"))
        self.assertFalse(ranking.is_ccq("x_step_8um_settling_time_s"))
        self.assertEqual(ranking.rest_noise_key("theta_z_step1_ccq_x_m_s_per_rad"),
                         "theta_z_step1_ccq_rest_noise_x_m_s_per_rad")

    def test_above_noise_is_twice_the_rest_value(self):
        self.assertTrue(ranking.above_noise(2.0, 1.0))
        self.assertFalse(ranking.above_noise(1.999, 1.0))
        self.assertFalse(ranking.above_noise(None, 1.0))
        self.assertFalse(ranking.above_noise(float("nan"), 1.0))

    def test_two_ccqs_at_the_noise_tie_however_far_apart(self):
        key = "y_step_2um_ccq_theta_y_rad_s_per_m"
        # 1.5x apart and non-overlapping, but both below 2x their rest CCQ.
        self.assertEqual(ranking.rank(key, (0.0052, 0.0051, 0.0052), (0.0035, 0.0033, 0.0035), 0.0049, 0.0035),
                         "tie: noise")

    def test_a_ccq_above_the_noise_is_ranked_lower_is_better(self):
        key = "x_move_14mm_ccq_theta_y_rad_s_per_m"
        ours, printed = (3.9e-4, 3.2e-4, 5.0e-4), (3.2e-2, 2.9e-2, 3.4e-2)
        self.assertEqual(ranking.rank(key, ours, printed, 1e-5, 1e-5), "a")
        self.assertEqual(ranking.rank(key, printed, ours, 1e-5, 1e-5), "b")

    def test_overlapping_ranges_tie(self):
        key = "y_step_2um_ccq_theta_z_rad_s_per_m"
        self.assertEqual(ranking.rank(key, (0.0029, 0.0018, 0.0036), (0.0052, 0.0031, 0.0066), 2e-4, 2e-4),
                         "tie: spread")
        self.assertEqual(ranking.rank("x_rest_rms_noise_m", (4.8e-10, 4.5e-10, 5.1e-10),
                                      (4.7e-10, 4.6e-10, 5.3e-10)), "tie: spread")

    def test_the_figures_own_sense(self):
        # Settling: lower is better; crossover, margin, bandwidth: higher is better.
        self.assertEqual(ranking.rank("x_step_8um_settling_time_s", (0.052, 0.0512, 0.0524),
                                      (0.0492, 0.0484, 0.0492)), "b")
        self.assertEqual(ranking.rank("x_loop_phase_margin_deg", (33.0, 32.5, 33.5), (28.0, 27.5, 28.5)), "a")
        self.assertEqual(ranking.rank("x_closed_loop_peak_dB", (7.8, 7.6, 7.9), (13.0, 12.0, 14.0)), "-")
        self.assertEqual(ranking.rank("x_loop_crossover_Hz", (50.4, 50.0, 51.0), (50.4, 50.0, 51.0)), "equal")
        self.assertEqual(ranking.rank("x_loop_crossover_Hz", (50.4, 50.0, 51.0), None), "-")


class PresetComparisonVerdict(unittest.TestCase):
    def test_the_verdict_reads_each_controllers_rest_noise(self):
        key = "theta_z_step1_ccq_x_m_s_per_rad"
        row = {"figure": key, "default": (4e-4, 3e-4, 5e-4), "paper": (1e-3, 9e-4, 1.1e-3),
               "default_rest": 3e-4, "paper_rest": 3e-4}
        self.assertEqual(preset_comparison.verdict(row, "default"), "ours")  # printed is above its noise
        row["paper_rest"] = 6e-4
        self.assertEqual(preset_comparison.verdict(row, "default"), "tie: noise")


if __name__ == "__main__":
    unittest.main()
