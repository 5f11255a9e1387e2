"""Runs every example in the README and docs/: each fenced ```sh block as a shell script and
each ```python block with the built module, in a scratch folder that holds the small images,
sequences, looks and profiles the examples name. A block that fails names its file and line.

    run_examples.py SOURCE_DIR BUILD_DIR SCRATCH_DIR

Blocks of other languages (text, json) are output and formats, not commands. The Quick
start's `./build.sh` commands are what CI itself runs, so they are not run again here.
"""
import glob
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import OpenImageIO as oiio

FENCE = re.compile(r"^```(\w*)\s*$")


def examples(path):
    """(language, first line number, code) of each fenced block of a markdown file."""
    blocks, language, start, code = [], None, 0, []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            fence = FENCE.match(line)
            if fence and language is None:
                language, start, code = fence.group(1), number, []
            elif line.startswith("```") and language is not None:
                blocks.append((language, start, "".join(code)))
                language = None
            elif language is not None:
                code.append(line)
    return blocks


def write_exr(path, pixels):
    out = oiio.ImageOutput.create(path)
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], oiio.HALF)
    out.open(path, spec)
    out.write_image(pixels.astype(np.float32))
    out.close()


def scene(width, height, seed):
    """A small scene-linear picture: a ramp over eight stops with some colour."""
    y, x = np.mgrid[0:height, 0:width].astype(np.float32)
    ramp = 0.18 * 2.0 ** (8 * x / width - 4)
    rng = np.random.default_rng(seed)
    tint = np.array([1.0, 0.9, 0.7], np.float32) + 0.1 * rng.random(3, np.float32)
    return (ramp[..., None] * tint * (0.6 + 0.4 * y[..., None] / height)).astype(np.float32)


def make_fixtures(folder, darkroom):
    """The files the examples read, at sizes that run in moments."""
    for name in ("render", "plate", "cg", "still"):
        write_exr(os.path.join(folder, name + ".exr"), scene(128, 64, len(name)))
    # A step wedge in lux-seconds: 0.001 .. 10 across the frame.
    wedge = np.repeat((10.0 ** np.linspace(-3, 1, 64, dtype=np.float32))[None, :, None], 16, 0)
    write_exr(os.path.join(folder, "wedge.exr"), np.repeat(wedge, 3, 2))
    for frame in range(1001, 1101):
        write_exr(os.path.join(folder, "plate.%04d.exr" % frame), scene(32, 16, frame))
    shutil.copy(os.path.join(SOURCE, "examples", "looks", "sh010.json"), folder)
    subprocess.run([darkroom, "grain", "predict", "--stock", "kodak-vision3-500t", "--width", "256", "-o",
                    os.path.join(folder, "plate-grain.json")], check=True, capture_output=True)


PYTHON_PRELUDE = """\
import numpy as np
pixels = np.full((32, 48, 3), 0.18, np.float32)
cg = np.full((32, 48, 4), 0.5, np.float32)
"""


def main():
    global SOURCE
    SOURCE, build, scratch = (os.path.abspath(a) for a in sys.argv[1:4])
    darkroom = os.path.join(build, "cli", "darkroom")
    shutil.rmtree(scratch, ignore_errors=True)
    os.makedirs(scratch)
    make_fixtures(scratch, darkroom)
    env = dict(os.environ, PATH=os.path.dirname(darkroom) + os.pathsep + os.environ["PATH"],
               PYTHONPATH=os.path.join(build, "python"))
    env.pop("OCIO", None)
    pages = [os.path.join(SOURCE, "README.md")] + sorted(glob.glob(os.path.join(SOURCE, "docs", "**", "*.md"),
                                                                   recursive=True))
    ran, failed = 0, []
    for page in pages:
        for language, line, code in examples(page):
            where = "%s:%d" % (os.path.relpath(page, SOURCE), line)
            if language == "sh" and code.lstrip().startswith("./build.sh"):
                continue
            if language == "sh":
                command = ["sh", "-e", "-c", code]
            elif language == "python":
                command = [sys.executable, "-c", PYTHON_PRELUDE + code]
            else:
                continue
            result = subprocess.run(command, cwd=scratch, env=env, capture_output=True, text=True, timeout=600)
            ran += 1
            if result.returncode != 0:
                failed.append(where)
                print("FAILED %s (exit %d)\n%s\n%s" % (where, result.returncode, code, result.stderr[-2000:]))
            else:
                print("ran %s" % where)
    print("%d examples run, %d failed" % (ran, len(failed)))
    if ran == 0 or failed:
        sys.exit(1)


if __name__ == "__main__":
    main()
