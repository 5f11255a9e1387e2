"""The OpenCue example: the job spec built offline has the shot's frame range and chunking,
and the command Cuebot would give each chunk develops exactly that chunk's frames.

Run by CTest in a virtual environment holding opencue-pyoutline (see make_opencue_venv.sh),
with DARKROOM_EXE naming the program and EXAMPLES_DIR the examples folder.
"""
import os
import shlex
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ElementTree

sys.path.insert(0, os.path.join(os.environ["EXAMPLES_DIR"], "opencue"))
import darkroom_job  # noqa: E402

DARKROOM_EXE = os.environ["DARKROOM_EXE"]


def cuebot_chunks(first, last, step, chunk):
    """Cuebot's frame set for FIRST-LASTxSTEP, split into chunks of `chunk` frames."""
    frames = list(range(first, last + 1, step))
    return [frames[i:i + chunk] for i in range(0, len(frames), chunk)]


def frames_flag(command):
    """The --frames value in a task's command ("/bin/sh -c SCRIPT")."""
    script = shlex.split(command)[2]
    words = shlex.split(script)
    return words[words.index("--frames") + 1]


def task_command(command, chunk_frames):
    """What Cuebot dispatches for one chunk: the command with its frame tokens replaced."""
    return (command.replace("#FRAME_START#", str(chunk_frames[0]))
            .replace("#FRAME_END#", str(chunk_frames[-1])))


class OpenCueJob(unittest.TestCase):
    def spec_layer(self, frame_range, chunk, **kwargs):
        job = darkroom_job.build_job("demo", "sh010", "/plates/plate.####.exr", "/renders/film.####.exr",
                                     frame_range, chunk, user="td", **kwargs)
        spec = ElementTree.fromstring(darkroom_job.job_spec(job, user="td").split("?>", 1)[1].split(">", 1)[1])
        self.assertEqual(spec.find("shot").text, "sh010")
        layers = spec.findall("job/layers/layer")
        self.assertEqual(len(layers), 1)
        return layers[0]

    def test_spec_has_the_frame_range_and_chunking(self):
        layer = self.spec_layer("1001-1100", 10, look="/looks/sh010.json", cores=4)
        self.assertEqual(layer.find("range").text, "1001-1100")
        self.assertEqual(layer.find("chunk").text, "10")
        self.assertEqual(float(layer.find("cores").text), 4.0)
        cmd = layer.find("cmd").text
        for part in ("develop", "--frames #FRAME_START#-#FRAME_END#", "${CUE_THREADS:-0}", "--no-clobber",
                     "--look /looks/sh010.json"):
            self.assertIn(part, cmd)

    def test_chunks_cover_every_frame_once(self):
        for frame_range, first, last, step, chunk in (("1001-1100", 1001, 1100, 1, 10),
                                                      ("1-95x2", 1, 95, 2, 7)):
            layer = self.spec_layer(frame_range, chunk)
            cmd = layer.find("cmd").text
            seen = []
            for frames in cuebot_chunks(first, last, step, chunk):
                flag = frames_flag(task_command(cmd, frames))
                lo, hi = (int(v) for v in flag.split("x")[0].split("-"))
                seen += list(range(lo, hi + 1, step))
            self.assertEqual(seen, list(range(first, last + 1, step)))

    def test_a_chunk_command_develops_its_frames(self):
        work = self.enterContext(tempfile.TemporaryDirectory(prefix="darkroom-opencue-"))
        plate = os.path.join(work, "plate.exr")
        subprocess.run(["oiiotool", "--pattern", "fill:top=0.1,0.1,0.1:bottom=0.9,0.6,0.3", "24x16", "3",
                        "-d", "float", "-o", plate], check=True)
        for frame in range(1, 6):
            os.link(plate, os.path.join(work, "plate.%04d.exr" % frame))
        command = darkroom_job.develop_command(DARKROOM_EXE, os.path.join(work, "plate.####.exr"),
                                               os.path.join(work, "film.####.exr"), "1-5",
                                               extra_args=["--no-grain", "--no-mtf"])
        env = dict(os.environ, CUE_THREADS="2")
        subprocess.run(task_command(command, [2, 3, 4]), shell=True, check=True, env=env)
        made = sorted(f for f in os.listdir(work) if f.startswith("film."))
        self.assertEqual(made, ["film.0002.exr", "film.0003.exr", "film.0004.exr"])

    def test_a_range_cuebot_cannot_chunk_by_tokens_is_refused(self):
        with self.assertRaises(ValueError):
            darkroom_job.chunk_frames_flag("1,5,9")


if __name__ == "__main__":
    unittest.main()
