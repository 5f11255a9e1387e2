"""The darkroom Python module develops numpy arrays exactly as the darkroom program does.

Run by CTest with PYTHONPATH at the built module and DARKROOM_EXE naming the program.
"""
import json
import os
import subprocess
import sys
import tempfile
import unittest
import warnings

import numpy as np
import OpenImageIO as oiio

import darkroom

DARKROOM_EXE = os.environ["DARKROOM_EXE"]


def read_exr(path):
    image = oiio.ImageInput.open(path)
    pixels = image.read_image(oiio.FLOAT)
    image.close()
    return pixels


def write_exr(path, pixels):
    out = oiio.ImageOutput.create(path)
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], oiio.FLOAT)
    spec.channelnames = ("R", "G", "B", "A")
    spec.alpha_channel = 3
    out.open(path, spec)
    out.write_image(pixels)
    out.close()


def run_program(*args):
    subprocess.run([DARKROOM_EXE, *args], check=True, capture_output=True)


class ModuleEqualsProgram(unittest.TestCase):
    def setUp(self):
        self.dir = self.enterContext(tempfile.TemporaryDirectory(prefix="darkroom-python-"))
        height, width = 30, 40
        y, x = np.mgrid[0:height, 0:width].astype(np.float32)
        self.plate = np.stack([0.02 + x / width, 0.05 + y / height, 0.1 + 0.5 * x * y / (width * height),
                               (x + y) / (width + height)], axis=-1).astype(np.float32)
        self.input = os.path.join(self.dir, "plate.exr")
        write_exr(self.input, self.plate)
        self.look = os.path.join(self.dir, "look.json")
        darkroom.save_look(self.look, seed=7, exposure=0.5, frame_width_mm=3, print_width_mm=20, output="print")

    def program(self, *flags):
        out = os.path.join(self.dir, "out.exr")
        run_program("develop", self.input, "-o", out, *flags)
        return read_exr(out)

    def test_same_pixels_from_the_same_look_and_frame(self):
        expected = self.program("--look", self.look, "--frame", "9")
        got = darkroom.develop(self.plate, look=self.look, frame=9)
        self.assertEqual(got.shape, expected.shape)
        self.assertTrue(np.array_equal(got, expected))
        self.assertTrue(np.array_equal(got[..., 3], self.plate[..., 3]))  # alpha passes through

    def test_a_plate_grain_profile_replaces_the_stock_grain_as_in_the_program(self):
        profile = os.path.join(self.dir, "plate-grain.json")
        run_program("grain", "predict", "--stock", "kodak-vision3-500t", "--width", "512", "-o", profile)
        with open(profile) as f:
            measured = json.load(f)
        measured["encoding"] = "linear"  # as if measured on linear plates, as the look's output is
        with open(profile, "w") as f:
            json.dump(measured, f)
        expected = self.program("--look", self.look, "--frame", "4", "--grain-profile", profile)
        got = darkroom.develop(self.plate, look=self.look, frame=4, grain_profile=profile)
        self.assertTrue(np.array_equal(got, expected))
        self.assertFalse(np.array_equal(got, darkroom.develop(self.plate, look=self.look, frame=4)))
        with self.assertRaisesRegex(darkroom.DarkroomError, "nonexistent-profile.json"):
            darkroom.develop(self.plate, look=self.look, grain_profile="/nonexistent-profile.json")

    def test_grain_apply_gives_the_programs_pixels(self):
        profile = os.path.join(self.dir, "element-grain.json")
        run_program("grain", "predict", "--stock", "kodak-vision3-500t", "--width", "512", "-o", profile)
        out = os.path.join(self.dir, "element-grained.exr")
        # A predicted profile is of a Cineon log scan: the program refuses a float EXR, linear
        # by its pixel type, unless told the element is log.
        run_program("grain", "apply", self.input, "--iscolorspace", "Cineon log", "--profile", profile, "-o", out,
                    "--seed", "3", "--frame", "7")
        got = darkroom.grain_apply(self.plate, profile, seed=3, frame=7, threads=1)
        self.assertEqual(got.shape, self.plate.shape)
        self.assertTrue(np.array_equal(got, read_exr(out)))
        self.assertTrue(np.array_equal(got[..., 3], self.plate[..., 3]))  # alpha untouched
        self.assertFalse(np.array_equal(got, self.plate))
        with self.assertRaisesRegex(darkroom.DarkroomError, "3 channels, the image 1 colour channel"):
            darkroom.grain_apply(self.plate[..., 0], profile)

    def test_premultiplied_colour_is_divided_by_alpha_and_multiplied_back(self):
        straight = self.plate.copy()
        straight[..., :3] /= np.where(self.plate[..., 3:] > 0, self.plate[..., 3:], 1)
        opaque = straight.copy()
        opaque[..., 3] = 1
        expected = darkroom.develop(opaque, look=self.look, frame=2)[..., :3] * self.plate[..., 3:]
        got = darkroom.develop(self.plate, look=self.look, frame=2)
        np.testing.assert_allclose(got[..., :3], expected, rtol=1e-5, atol=1e-7)
        self.assertTrue(np.all(got[self.plate[..., 3] == 0][..., :3] == 0))
        # premultiplied=False: the colour is developed as it is (as with an opaque alpha), the
        # alpha passed through.
        plate_opaque = self.plate.copy()
        plate_opaque[..., 3] = 1
        as_straight = darkroom.develop(self.plate, look=self.look, frame=2, premultiplied=False)
        self.assertTrue(np.array_equal(as_straight[..., :3], darkroom.develop(plate_opaque, look=self.look, frame=2)[..., :3]))
        self.assertTrue(np.array_equal(as_straight[..., 3], self.plate[..., 3]))

    def test_keywords_override_the_look_file_as_flags_do(self):
        expected = self.program("--look", self.look, "--frame", "3", "--exposure", "-1", "--no-mtf")
        got = darkroom.develop(self.plate, look=self.look, frame=3, exposure=-1, mtf=False, threads=1)
        self.assertTrue(np.array_equal(got, expected))
        self.assertFalse(np.array_equal(got, darkroom.develop(self.plate, look=self.look, frame=3)))

    def test_the_module_and_the_program_write_the_same_look(self):
        from_program = os.path.join(self.dir, "program-look.json")
        run_program("develop", "--save-look", from_program, "--seed", "7", "--exposure", "0.5",
                    "--frame-width-mm", "3", "--print-width-mm", "20")
        with open(from_program) as f, open(self.look) as g:
            self.assertEqual(json.load(f), json.load(g))
        self.assertEqual(darkroom.look(look=self.look)["settings"]["seed"], 7)

    def test_working_memory_is_kept_for_the_next_image_until_released(self):
        # 512x512 planes (1 MiB each) are pooled; the 30x40 plate's are not. (The texture
        # output runs stage after stage over whole planes; the fast tier's print keeps none.)
        big = np.resize(self.plate, (512, 512, 4))
        darkroom.release_memory()
        darkroom.develop(big, look=self.look, frame=1, output="texture")
        self.assertGreaterEqual(darkroom.release_memory(), 512 * 512 * 4)
        self.assertEqual(darkroom.release_memory(), 0)

    def test_an_hours_long_reference_render_warns_before_it_starts(self):
        # 30x40 pixels across a whole Super 35 frame: tens of millions of silver grains a
        # pixel. With the warning made an error the render never starts.
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            with self.assertRaisesRegex(RuntimeWarning, "draws every silver grain.*CPU hours"):
                darkroom.develop(self.plate, quality="reference")

    def test_a_reference_render_over_its_budget_is_refused_as_an_error(self):
        # The same plate across a 150 mm frame: days of CPU, refused before it starts.
        with self.assertRaisesRegex(ValueError, "quality=reference.*budget of 24 CPU hours"):
            darkroom.develop(self.plate, quality="reference", frame_width_mm=150, print_width_mm=150)

    def test_non_finite_input_is_warned_of_as_the_program_does(self):
        # Colour and the premultiplying alpha are counted; the result stays finite.
        plate = self.plate.copy()
        plate[0, 0, 0] = np.nan
        plate[1, 1, 1] = np.inf
        plate[2, 2, 3] = np.nan
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            out = darkroom.develop(plate, look=self.look, frame=1)
        messages = [str(w.message) for w in caught if issubclass(w.category, RuntimeWarning)]
        self.assertIn("darkroom: 2 non-finite colour values (NaN and -Inf count as no light, +Inf as 1e30)", messages)
        self.assertTrue(any("1 non-finite alpha values" in m for m in messages), messages)
        self.assertTrue(np.isfinite(out[..., :3]).all())
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            darkroom.develop(self.plate, look=self.look, frame=1)
        self.assertEqual([w for w in caught if "non-finite" in str(w.message)], [])

    def test_every_output_mode_of_a_look_file_gives_the_programs_pixels(self):
        for output in ("print", "negative", "density", "scan", "texture"):
            with self.subTest(output=output):
                look = os.path.join(self.dir, output + ".json")
                darkroom.save_look(look, look=self.look, output=output, quality="high" if output == "density" else "fast")
                expected = self.program("--look", look, "--frame", "3")
                got = darkroom.develop(self.plate, look=look, frame=3)
                self.assertTrue(np.array_equal(got, expected))

    def test_bad_settings_are_named(self):
        with self.assertRaisesRegex(TypeError, "exposur.*did you mean 'exposure'"):
            darkroom.develop(self.plate, exposur=1)
        with self.assertRaisesRegex(ValueError, "output= must be one of print"):
            darkroom.develop(self.plate, output="slide")
        with self.assertRaisesRegex(ValueError, "seed= must be a whole number"):
            darkroom.develop(self.plate, seed=2**64)
        self.assertEqual(darkroom.look(seed=2**64 - 1)["settings"]["seed"], 2**64 - 1)
        bad = os.path.join(self.dir, "bad.json")
        with open(bad, "w") as f:
            json.dump({"format": "darkroom-look", "version": 1, "settings": {"threads": 2}}, f)
        with self.assertRaisesRegex(ValueError, "bad.json.*run option"):
            darkroom.develop(self.plate, look=bad)


class TheParameterTable(unittest.TestCase):
    """The keywords, the program's flags and look files are one table, with one schema."""

    def test_the_keywords_defaults_and_ranges_are_the_programs(self):
        folder = self.enterContext(tempfile.TemporaryDirectory(prefix="darkroom-table-"))
        path = os.path.join(folder, "defaults.json")
        run_program("develop", "--save-look", path)
        with open(path) as f:
            program = json.load(f)["settings"]
        table = {row["key"]: row for row in darkroom.parameters()}
        self.assertEqual(set(table), set(program))
        for key, row in table.items():
            with self.subTest(key=key):
                self.assertEqual(row["default"], program[key])
                self.assertEqual(row["keyword"], key.replace("-", "_"))
                if "min" not in row:
                    continue
                # Past the range, the keyword and the flag are refused alike.
                value = row["max"] + 1
                with self.assertRaisesRegex(ValueError, row["keyword"] + "= must be a number from"):
                    darkroom.look(**{row["keyword"]: value})
                result = subprocess.run([DARKROOM_EXE, "develop", "--" + key, str(value), "--save-look",
                                         os.path.join(folder, "refused.json")], capture_output=True, text=True)
                self.assertEqual(result.returncode, 105)  # (a value out of range: docs/reference/exit-codes.md)
                self.assertIn("--" + key + ": must be a number from", result.stderr)

    def test_the_schema_and_reference_in_the_repository_are_the_tables(self):
        sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "tools"))
        import write_look_reference
        stale = "out of date: run tools/write_look_reference.py"
        with open(SCHEMA) as f:
            self.assertEqual(json.load(f), darkroom.look_schema(), "docs/reference/schemas/look.schema.json is " + stale)
        with open(PARAMETERS_PAGE) as f:
            self.assertEqual(f.read(), write_look_reference.parameters_page(), "docs/reference/look-parameters.md is " + stale)

    def test_the_schema_takes_looks_and_refuses_broken_ones(self):
        import jsonschema
        schema = darkroom.look_schema()
        jsonschema.Draft202012Validator.check_schema(schema)
        validator = jsonschema.Draft202012Validator(schema)
        for name in ("default-v1.json", "tri-x-v1.json"):
            with open(os.path.join(LOOK_DATA, name)) as f:
                validator.validate(json.load(f))
        validator.validate(darkroom.look(film="kodak-tri-x-400", grain_amount=[0.5, 1, 2], seed=2**64 - 1,
                                         ociodisplay=["sRGB", "Film"]))
        good = darkroom.look()
        folder = self.enterContext(tempfile.TemporaryDirectory(prefix="darkroom-look-"))
        for key, bad in (("exposure", 65), ("grain-amount", [1, 2]), ("output", "slide"), ("seed", -1),
                         ("grain", 1), ("ociodisplay", ["sRGB"]), ("exposur", 0)):
            with self.subTest(key=key):
                broken = json.loads(json.dumps(good))
                broken["settings"][key] = bad
                self.assertFalse(validator.is_valid(broken))
                with self.assertRaises((ValueError, TypeError)):
                    path = os.path.join(folder, "broken.json")
                    with open(path, "w") as f:
                        json.dump(broken, f)
                    darkroom.look(look=path)


SCHEMA = os.path.join(os.path.dirname(__file__), "..", "..", "docs", "reference", "schemas", "look.schema.json")
PARAMETERS_PAGE = os.path.join(os.path.dirname(__file__), "..", "..", "docs", "reference", "look-parameters.md")
LOOK_DATA = os.path.join(os.path.dirname(__file__), "..", "look", "data")


if __name__ == "__main__":
    unittest.main()
