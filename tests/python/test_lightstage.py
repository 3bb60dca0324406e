"""The lightstage Python module against the lightstage CLI, on simulated and real stacks."""
import json
import os
import pathlib
import shutil
import subprocess
import tempfile
import unittest

import numpy as np

import lightstage

BIN = pathlib.Path(os.environ["LIGHTSTAGE_BIN"])
SOURCE = pathlib.Path(os.environ["LIGHTSTAGE_SOURCE_DIR"])


def shared_data():
    """LIGHTSTAGE_SHARED_DATA, else ../shared/data beside the checkout (None when neither is there)."""
    given = os.environ.get("LIGHTSTAGE_SHARED_DATA")
    for candidate in ([pathlib.Path(given)] if given else []) + [SOURCE.parent / "shared" / "data"]:
        if (candidate / "diligent").is_dir():
            return candidate
    return None


def cli(*args):
    run = subprocess.run([str(BIN / "lightstage"), *map(str, args)], capture_output=True, text=True)
    if run.returncode != 0:
        raise AssertionError(f"lightstage {' '.join(map(str, args))} failed: {run.stderr}")
    return run.stdout


class Scratch(unittest.TestCase):
    def setUp(self):
        root = pathlib.Path(os.environ.get("LIGHTSTAGE_SCRATCH", tempfile.gettempdir()))
        root.mkdir(parents=True, exist_ok=True)
        self.dir = pathlib.Path(tempfile.mkdtemp(prefix=self.id().split(".")[-1] + "-", dir=root))

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def sphere_stack(self, size=48):
        stack = self.dir / "stack"
        cli("simulate", "--scene", "sphere", "--lights", "distant", "--width", size, "--height", size,
            "--out", stack, "--quiet")
        return stack


class Module(Scratch):
    def test_lists_the_clis_methods(self):
        names = [name for name, _ in lightstage.methods()]
        self.assertEqual(names[:3], ["l2", "robust", "monotonic"])
        self.assertIn("shape-prior", names)
        self.assertTrue(lightstage.__version__)

    def test_loads_a_stack(self):
        stack = lightstage.load_stack(self.sphere_stack())
        self.assertEqual(len(stack["images"]), 96)
        self.assertEqual(stack["images"][0].shape[:2], (48, 48))
        self.assertEqual(stack["light_directions"].shape, (96, 3))
        np.testing.assert_allclose(np.linalg.norm(stack["light_directions"], axis=1), 1, atol=1e-9)
        self.assertEqual(stack["mask"].dtype, np.bool_)
        self.assertEqual(stack["normals_gt"].shape, (48, 48, 3))

    def test_solves_like_the_cli(self):
        stack = self.sphere_stack()
        for method in ["l2", "biquadratic"]:
            result = lightstage.solve(stack, method, shadow_threshold=0.02)
            out = self.dir / method
            cli("solve", "--input", stack, "--method", method, "--shadow-threshold", "0.02", "--out", out, "--quiet")
            summary = json.loads((out / "summary.json").read_text())
            self.assertEqual(result["summary"]["method"], method)
            self.assertEqual(result["summary"]["pixels_solved"], summary["pixels_solved"])
            self.assertAlmostEqual(result["summary"]["error_vs_ground_truth"]["mean_deg"],
                                   summary["error_vs_ground_truth"]["mean_deg"], places=9)
            # Bit for bit the CLI's float outputs; normal.png to its 16-bit step.
            np.testing.assert_array_equal(result["normals"], lightstage.read_exr(out / "normal.exr", ["R", "G", "B"]))
            np.testing.assert_array_equal(result["albedo"], lightstage.read_pfm(out / "albedo.pfm"))
            np.testing.assert_array_equal(result["residual"], lightstage.read_pfm(out / "residual.pfm"))
            normals, valid = lightstage.read_normal_map(out / "normal.png")
            np.testing.assert_array_equal(valid, result["solved"])
            np.testing.assert_allclose(result["normals"], normals, atol=2.0 / 65535)
        # biquadratic: C_ij, i, j in 0..2, then the specular lobe's weight when the relighting fit chose one
        lobe = "specular" in result["summary"]["reflectance"]
        self.assertEqual(result["coefficients"].shape[2], 10 if lobe else 9)

    def test_integrates_and_measures(self):
        stack = self.sphere_stack()
        result = lightstage.solve(stack, "l2", shadow_threshold=0.02)
        truth = lightstage.load_stack(stack)["normals_gt"]
        error = lightstage.angular_error(result["normals"], truth, result["solved"])
        self.assertLess(error["mean_deg"], 1.0)
        self.assertEqual(error["degrees"].shape, (48, 48))
        surface = lightstage.integrate(result["normals"], result["solved"])
        depth, valid = surface["depth"], surface["valid"]
        self.assertEqual(depth.shape, (48, 48))
        # A sphere bulges toward the camera: its centre stands above its rim.
        self.assertGreater(depth[24, 24], depth[valid].mean())

    def test_calibrates_lights_from_a_chrome_sphere(self):
        chrome = self.dir / "chrome"
        cli("simulate", "--scene", "chrome-probe", "--width", 256, "--out", chrome, "--quiet")
        calibration = lightstage.calibrate_lights([chrome], rig=SOURCE / "hw/rigs/sim-dome.yaml")
        directions = calibration["directions"]
        self.assertEqual(directions.shape, (96, 3))
        truth = lightstage.load_stack(chrome)["light_directions"]
        cosines = np.clip(np.sum(directions * truth, axis=1), -1, 1)
        self.assertLess(np.degrees(np.arccos(cosines)).mean(), 1.0)

    def test_bad_input_names_the_option_or_file(self):
        with self.assertRaisesRegex(TypeError, "shadow_treshold"):
            lightstage.solve(self.dir, "l2", shadow_treshold=0.02)
        with self.assertRaisesRegex(lightstage.InputError, "--method"):
            lightstage.solve(self.dir, "lambertian")
        with self.assertRaises(ValueError):  # InputError is a ValueError
            lightstage.solve(self.dir / "missing", "l2")
        with self.assertRaisesRegex(ValueError, "normals"):
            lightstage.integrate(np.zeros((4, 4)))


@unittest.skipIf(shared_data() is None, "no real data (LIGHTSTAGE_SHARED_DATA or ../shared/data)")
class DiligentBall(Scratch):
    def test_l2_reproduces_the_published_baseline_and_the_cli(self):
        ball = shared_data() / "diligent" / "ballPNG"
        result = lightstage.solve(ball, "l2")
        self.assertAlmostEqual(result["summary"]["error_vs_ground_truth"]["mean_deg"], 4.10, delta=0.01)
        out = self.dir / "ball"
        cli("solve", "--input", ball, "--out", out, "--quiet")
        np.testing.assert_array_equal(result["normals"], lightstage.read_exr(out / "normal.exr", ["R", "G", "B"]))
        np.testing.assert_array_equal(result["albedo"], lightstage.read_pfm(out / "albedo.pfm"))
        normals, valid = lightstage.read_normal_map(out / "normal.png")
        np.testing.assert_array_equal(valid, result["solved"])
        np.testing.assert_allclose(result["normals"], normals, atol=2.0 / 65535)


if __name__ == "__main__":
    unittest.main()
