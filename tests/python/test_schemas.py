"""The file formats' JSON Schemas (docs/reference/schemas/) take the files Darkroom ships and
writes, and refuse broken ones. Run by CTest with Debian's python3-jsonschema and DARKROOM_EXE
naming the program (which measures a grain profile for the test)."""
import copy
import glob
import json
import os
import subprocess
import tempfile
import unittest

import jsonschema

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
SCHEMAS = os.path.join(ROOT, "docs", "reference", "schemas")


def validator(name):
    with open(os.path.join(SCHEMAS, name + ".schema.json")) as f:
        schema = json.load(f)
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def load(path):
    with open(path) as f:
        return json.load(f)


class StockSchema(unittest.TestCase):
    def setUp(self):
        self.schema = validator("stock")
        self.stocks = sorted(glob.glob(os.path.join(ROOT, "core", "stocks", "*.json")))

    def test_every_built_in_stock_is_valid(self):
        self.assertGreaterEqual(len(self.stocks), 14)
        for path in self.stocks:
            with self.subTest(stock=os.path.basename(path)):
                self.schema.validate(load(path))

    def test_broken_stocks_are_refused(self):
        good = load(os.path.join(ROOT, "core", "stocks", "kodak-vision3-250d.json"))
        breakages = {
            "an unknown kind": lambda s: s.update(kind="slide"),
            "no layers": lambda s: s.update(layers=[]),
            "a granularity above 1": lambda s: s["layers"][0]["grain"].update(rms_granularity=3),
            "an unknown field": lambda s: s.update(colour="orange"),
            "a layer without its curve": lambda s: s["layers"][1].pop("density_curve"),
            "a Gaussian without its width": lambda s: s["layers"][0]["spectral_sensitivity"]["gaussians"][0].pop("sigma_nm"),
            "another format": lambda s: s.update(format="darkroom-look"),
            # A softplus curve starts from d_min (rising) or, for a reversal film, d_max: one of them.
            "a softplus curve with no start": lambda s: s["layers"][0]["density_curve"]["softplus"].pop("d_min"),
            "a softplus curve with two starts":
                lambda s: s["layers"][0]["density_curve"]["softplus"].update(d_max=2.5),
        }
        for what, breakage in breakages.items():
            with self.subTest(what):
                broken = copy.deepcopy(good)
                breakage(broken)
                self.assertFalse(self.schema.is_valid(broken))


class GrainProfileSchema(unittest.TestCase):
    def test_profiles_as_darkroom_writes_them_are_valid_and_broken_ones_refused(self):
        schema = validator("grain-profile")
        profiles = glob.glob(os.path.join(ROOT, "examples", "grain-profiles", "*.json"))
        self.assertGreaterEqual(len(profiles), 1)
        # And one measured from a plate: grain put on a grey ramp, analysed back.
        darkroom = os.environ["DARKROOM_EXE"]
        folder = self.enterContext(tempfile.TemporaryDirectory(prefix="darkroom-schema-"))
        ramp, grained, measured = (os.path.join(folder, n) for n in ("ramp.exr", "grained.exr", "measured.json"))
        subprocess.run(["oiiotool", "--pattern", "fill:left=0.15,0.15,0.15:right=0.9,0.9,0.9", "512x256", "3",
                        "-d", "float", "-o", ramp], check=True)
        subprocess.run([darkroom, "grain", "apply", ramp, "-o", grained, "--profile", profiles[0],
                        "--iscolorspace", "Cineon Log"], check=True, capture_output=True)
        subprocess.run([darkroom, "grain", "analyze", grained, "-o", measured, "--iscolorspace", "Cineon Log"],
                       check=True, capture_output=True)
        for path in profiles + [measured]:
            with self.subTest(profile=os.path.basename(path)):
                schema.validate(load(path))
        good = load(profiles[0])
        breakages = {
            "another encoding": lambda p: p.update(encoding="gamma"),
            "no channels": lambda p: p.update(channels=[]),
            "a negative sigma": lambda p: p["channels"][0]["response"]["sigma"].__setitem__(0, -1),
            "no autocorrelation": lambda p: p["channels"][1].pop("autocorrelation"),
            "another version": lambda p: p.update(version=2),
        }
        for what, breakage in breakages.items():
            with self.subTest(what):
                broken = copy.deepcopy(good)
                breakage(broken)
                self.assertFalse(schema.is_valid(broken))


class LookSchema(unittest.TestCase):
    def test_the_example_looks_are_valid_and_broken_ones_refused(self):
        schema = validator("look")
        looks = sorted(glob.glob(os.path.join(ROOT, "examples", "looks", "*.json")) +
                       glob.glob(os.path.join(ROOT, "tests", "look", "data", "*.json")))
        self.assertGreaterEqual(len(looks), 3)
        for path in looks:
            with self.subTest(look=os.path.basename(path)):
                schema.validate(load(path))
        broken = load(looks[0])
        broken["settings"]["printer-lights"] = [25, 25]
        self.assertFalse(schema.is_valid(broken))


if __name__ == "__main__":
    unittest.main()
