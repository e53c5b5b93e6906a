"""hystloop.identify_stage: a known sampled stage's dynamics from a periodic multisine record."""
import math
import unittest

import numpy as np

import hystloop

FS = 1e4  # [Hz] the bridge's tick rate
N = 1000  # samples per period: 10 Hz lines


def multisine(lines, periods, seed=1):
    rng = np.random.default_rng(seed)
    k = np.arange(N * periods)
    u = np.zeros(k.size)
    for line in lines:
        u += np.cos(2 * np.pi * line * k / N + rng.uniform(0, 2 * np.pi))
    return u / np.std(u)


def first_order(u, fc_hz, gain, noise_m=0.0, seed=2):
    """The zero-order-held first-order stage gain / (1 + s / wc), y_k at the end of tick k."""
    a = math.exp(-2 * math.pi * fc_hz / FS)
    y = np.zeros(u.size)
    prev = 0.0
    for k in range(u.size):
        prev = a * prev + (1 - a) * gain * u[k]
        y[k] = prev
    return y + np.random.default_rng(seed).normal(0.0, noise_m, u.size)


class IdentifyStage(unittest.TestCase):
    def test_a_first_order_stage_is_found_with_its_gain_and_no_delay(self):
        lines = range(1, 300)  # 10 Hz .. 3 kHz
        u = multisine(lines, periods=4)
        y = first_order(u, fc_hz=500.0, gain=6e-9, noise_m=1e-11)
        st = hystloop.identify_stage(u, y, period_samples=N, periods=4, band=(10.0, 2990.0), order="0/1")
        self.assertEqual(st["order"], "0/1")
        self.assertAlmostEqual(st["dc_gain"] / 6e-9, 1.0, delta=1e-3)
        self.assertEqual(len(st["poles_hz"]), 1)
        self.assertAlmostEqual(-st["poles_hz"][0].real / 500.0, 1.0, delta=1e-2)
        self.assertLess(st["delay_s"], 2e-6)  # no delay: a fiftieth of a tick
        g = np.asarray(st["G"])
        model = np.asarray(st["model_G"])
        self.assertEqual(g.size, len(st["frequency_Hz"]))
        self.assertLess(np.max(np.abs(g - model) / np.abs(model)), 0.01)
        self.assertTrue(np.all(np.asarray(st["sigma"]) > 0))

    def test_through_the_hysteresis_the_gain_is_the_plays_and_u_to_y_is_kept_apart(self):
        lines = range(1, 300)
        u = multisine(lines, periods=4)
        y = first_order(u, fc_hz=500.0, gain=6e-9, noise_m=1e-11)
        through = hystloop.identify_stage(u, y, period_samples=N, periods=4, band=(10.0, 2990.0), order="0/1",
                                          hysteresis_plays=15)
        alone = hystloop.identify_stage(u, y, period_samples=N, periods=4, band=(10.0, 2990.0), order="0/1")
        self.assertTrue(through["through_hysteresis"])
        self.assertFalse(alone["through_hysteresis"])
        self.assertTrue(math.isnan(alone["residual_rms"]))
        # No hysteresis here: the linear play carries the gain, the stage is the same, G has unit DC gain.
        self.assertEqual(len(through["hysteresis_weights"]), 15)
        self.assertAlmostEqual(through["hysteresis_weights"][0] / 6e-9, 1.0, delta=1e-2)
        self.assertAlmostEqual(through["dc_gain"], alone["dc_gain"], delta=1e-12)
        self.assertAlmostEqual(abs(np.asarray(through["G"])[0]), 1.0, delta=1e-2)
        self.assertAlmostEqual(through["poles_hz"][0].real / alone["poles_hz"][0].real, 1.0, delta=1e-2)
        self.assertLessEqual(through["residual_rms"], through["residual_rms_linear"] * 1.01)
        self.assertEqual(through["hysteresis_not_kept"], "")

    def test_refusals_name_the_parameter(self):
        u = multisine(range(1, 50), periods=4)
        with self.assertRaises(hystloop.ParameterError) as e:
            hystloop.identify_stage(u, u, period_samples=N, periods=4, order="two/four")
        self.assertEqual(e.exception.field, "order")
        with self.assertRaises(hystloop.ParameterError):
            hystloop.identify_stage(u[:-1], u[:-1], period_samples=N, periods=4)  # not whole periods


if __name__ == "__main__":
    unittest.main()
