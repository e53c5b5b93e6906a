"""hystloop.Rig against a live rig: hystloop-bridge (the simulated stage) and hystloop-compensator
started here, inside the private network namespace ctest runs this in (tools/netns-run). Every
request is acknowledged as hystloop-ctl's is, a refusal comes back as RigError with the
compensator's reason, record() returns every tick with none missing, and a rig that is not there
is said so within the timeout."""

import os
import subprocess
import sys
import tempfile
import time
import unittest

import numpy as np

import hystloop
from tool_support import tool


def start(args, log):
    return subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT)


class LiveRig(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        if os.environ.get("HYSTLOOP_NETNS") != "1":
            raise unittest.SkipTest("needs the private network namespace (tools/netns-run)")
        bridge = tool("HYSTLOOP_BRIDGE_EXE")
        compensator = tool("HYSTLOOP_COMPENSATOR_EXE")
        config = os.path.join(os.environ["HYSTLOOP_SOURCE_DIR"], "deploy", "config")
        cls.dir = tempfile.TemporaryDirectory()
        cls.logs = [open(os.path.join(cls.dir.name, n), "w") for n in ("compensator.log", "bridge.log")]
        cls.procs = [
            start([compensator, "--config", os.path.join(config, "compensator.yaml"),
                   "--set", "trajectory.shape=cosine", "--set", "trajectory.amplitude_m=-1.6e-6"], cls.logs[0]),
            start([bridge, "--config", os.path.join(config, "bridge.yaml")], cls.logs[1]),
        ]
        cls.rig = hystloop.Rig(timeout=5.0)
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline:
            s = cls.rig.status(listen=1.2)  # every process reports once a second
            if "bridge" in s and "compensator" in s and s["compensator"]["state"] != "STARTING":
                break
        else:
            tail = cls.log_tail()
            cls.tearDownClass()
            raise AssertionError(f"the rig did not come up ({s}): {tail}")

    @classmethod
    def tearDownClass(cls):
        for p in cls.procs:
            p.terminate()
        for p in cls.procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()
        for f in cls.logs:
            f.close()
        cls.dir.cleanup()

    @classmethod
    def log_tail(cls):
        out = ""
        for n in ("compensator.log", "bridge.log"):
            with open(os.path.join(cls.dir.name, n)) as f:
                out += f"\n== {n}\n" + "".join(f.readlines()[-15:])
        return out

    def counter(self, process, name):
        return self.rig.status(listen=1.2)[process]["counters"].get(name)

    def test_1_status_names_every_process_with_its_counters(self):
        s = self.rig.status(listen=1.2)
        self.assertIn(s["bridge"]["state"], ("SAFE", "HEALTHY", "DEGRADED"))
        self.assertEqual(s["bridge"]["counters"]["armed"], 0)  # it starts in the safe state
        self.assertIn("mode", s["compensator"]["counters"])

    def test_2_arm_gains_and_a_trajectory_are_acknowledged(self):
        self.rig.arm()
        self.assertEqual(self.counter("bridge", "armed"), 1)
        self.rig.set_gains(kp=0.04, axis=0)
        self.assertEqual(self.counter("bridge", "servo_kp_ppm"), 40000)
        self.rig.set_gains(kp=0.05)  # every axis
        verdict = self.rig.set_trajectory("cosine", amplitude_m=1e-6, frequency_Hz=1.0, blend_s=0.2)
        self.assertTrue(verdict.startswith("accepted"), verdict)
        # Beyond the actuator's range: refused by the compensator, its reason in the error.
        with self.assertRaises(hystloop.RigError) as e:
            self.rig.set_trajectory("sine", amplitude_m=1e-3, frequency_Hz=1.0)
        self.assertIn("refused trajectory", str(e.exception))
        with self.assertRaises(hystloop.ParameterError):
            self.rig.set_trajectory("zigzag", amplitude_m=1e-6)
        self.rig.learn("off")

    def test_3_record_returns_every_tick(self):
        r = self.rig.record(2.0)
        n = len(r["seq"])
        self.assertEqual(r["axes"], 1)
        self.assertEqual(r["missing_ticks"], 0)
        self.assertGreater(n, 19000)  # 2 s at 10 kHz
        self.assertTrue(np.all(np.diff(r["seq"]) == 1), "ticks in order, none twice")
        self.assertEqual(r["dt_s"], 1e-4)
        self.assertTrue(np.allclose(r["t_s"], r["seq"] * 1e-4))
        # The simulated stage's truth joined to its ticks (a block's truth may still be on its way).
        self.assertGreater(np.count_nonzero(np.isfinite(r["y_true_m"])), n - 200)
        # Tracking the 1 um cosine: within tens of nanometres of the reference at every tick.
        ok = np.isfinite(r["y_ref_m"]) & np.isfinite(r["y_true_m"])
        self.assertGreater(np.count_nonzero(ok), n // 2, self.log_tail())
        self.assertLess(float(np.max(np.abs(r["y_ref_m"][ok] - r["y_true_m"][ok]))), 5e-8)

    def test_4_blocks_stream_live(self):
        blocks = list(self.rig.blocks(timeout=1.0, count=3))
        self.assertEqual(len(blocks), 3)
        self.assertGreater(blocks[1]["seq"][0], blocks[0]["seq"][0])

    def run_example(self, name, *args, out=True):
        """An example of examples/, headless, on this rig: its exit status and output."""
        script = os.path.join(os.environ["HYSTLOOP_SOURCE_DIR"], "examples", name)
        out = os.path.join(self.dir.name, name) if out else None
        env = dict(os.environ, MPLBACKEND="Agg")
        p = subprocess.run([sys.executable, script, *(["--out", out] if out else []), *args], capture_output=True,
                           text=True, timeout=120, env=env)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr + self.log_tail())
        return out, p.stdout

    def test_5_the_mem_paper_example_runs(self):
        out, text = self.run_example("mem_paper.py", "--seconds", "2")
        self.assertTrue(os.path.getsize(os.path.join(out, "mem_paper.png")) > 10000)
        with open(os.path.join(out, "mem_paper.csv")) as f:
            rows = {r.split(",")[0]: float(r.split(",")[1]) for r in f.read().splitlines()[1:]}
        self.assertLess(rows["mem"], rows["linear"], text)
        # The gains it turned off are back.
        self.assertEqual(self.counter("bridge", "servo_kp_ppm"), 50000)

    def test_6_the_scan_learning_example_runs(self):
        out, text = self.run_example("scan_learning.py", "--seconds", "2")
        self.assertTrue(os.path.getsize(os.path.join(out, "scan_learning.png")) > 10000)
        self.assertIn("learning off", text)

    def test_7_the_record_example_runs(self):
        _, text = self.run_example("record.py", "--seconds", "1", "--polls", "1", out=False)
        self.assertIn("missing 0, in order True", text)

    def test_8_disarm_is_acknowledged(self):
        self.rig.disarm()
        self.assertEqual(self.counter("bridge", "armed"), 0)


class NoRig(unittest.TestCase):
    def test_a_request_without_a_rig_ends_within_its_timeout(self):
        rig = hystloop.Rig(url="memq://", timeout=0.3)  # nothing leaves this process
        start = time.monotonic()
        with self.assertRaises(hystloop.RigError) as e:
            rig.arm()
        self.assertLess(time.monotonic() - start, 2.0)
        self.assertIn("no rig is running", str(e.exception))
        self.assertEqual(rig.status(listen=0.1), {})
        self.assertIsNone(rig.next_block(timeout=0.1))
        with self.assertRaises(hystloop.RigError):
            rig.record(0.2)

    def test_a_url_off_this_host_needs_allow_network(self):
        with self.assertRaises(hystloop.ParameterError) as e:
            hystloop.Rig(url="udpm://239.255.76.67:7667?ttl=1")
        self.assertIn("allow", str(e.exception))

    def test_a_rig_file_names_the_rig(self):
        lab = os.path.join(os.environ["HYSTLOOP_SOURCE_DIR"], "deploy", "rig.yaml")
        with self.assertRaises(hystloop.ParameterError) as e:  # ttl 1: the lab's network
            hystloop.Rig.from_rig_file(lab, key_file="")
        self.assertIn("allow", str(e.exception))
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "rig.yaml")
            with open(path, "w") as f:
                f.write('rig: {prefix: LAB_, lcm_url: "udpm://239.255.76.67:7667", ttl: 0}\n')
            self.assertTrue(hystloop.Rig.from_rig_file(path).url.startswith("udpm://239.255.76.67:7667?ttl=0"))
            with open(path, "w") as f:
                f.write('rig: {lcm_url: "udpm://239.255.76.67:7667?ttl=0", ttl: 0}\n')
            with self.assertRaises(hystloop.ParameterError) as e:
                hystloop.Rig.from_rig_file(path)
            self.assertEqual(e.exception.field, "rig.lcm_url")

    def test_help_gives_units(self):
        self.assertIn("[1/s]", hystloop.Rig.set_gains.__doc__)
        self.assertIn("[s]", hystloop.Rig.record.__doc__)


if __name__ == "__main__":
    unittest.main()
