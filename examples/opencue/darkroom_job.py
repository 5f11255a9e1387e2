#!/usr/bin/env python3
"""An OpenCue job that develops a shot with darkroom: one layer, one command per chunk of frames.

    darkroom_job.py --show demo --shot sh010 \\
        --input /plates/sh010/plate.####.exr --output /renders/sh010/film.####.exr \\
        --frames 1001-1100 --chunk 10 --look /looks/sh010.json [--launch]

Without --launch it prints the job specification (XML) it would submit, which needs no
Cuebot. The chunk is the farm's unit of work: each task runs

    darkroom develop IN -o OUT --frames #FRAME_START#-#FRAME_END# --threads $CUE_THREADS --no-clobber

Cuebot replaces the #FRAME_START#/#FRAME_END# tokens with the chunk's first and last frame;
RQD sets CUE_THREADS to the cores booked for the task. --no-clobber makes a retried task
resume where the failed attempt stopped (each finished frame is complete: darkroom writes
to a temporary name and renames).

Needs the opencue-pyoutline package (pip install opencue-pyoutline packaging).
"""
import argparse
import re
import shlex

import outline
import outline.cuerun
from outline.modules.shell import Shell

# "1001-1100" or "1001-1100x2": Cuebot's chunk tokens name a chunk's first and last frame,
# so a stepped range passes its step on to darkroom.
_RANGE = re.compile(r"^(-?\d+)-(-?\d+)(?:x(\d+))?$")
# Characters a shell word may hold unquoted; '#' inside a word is not a comment.
_SHELL_SAFE = re.compile(r"^[\w@%+=:,./#-]+$")


def _shell_word(arg):
    return arg if _SHELL_SAFE.match(arg) and not arg.startswith("#") else shlex.quote(arg)


def chunk_frames_flag(frame_range):
    """The --frames value for one chunk, in Cuebot's tokens."""
    match = _RANGE.match(frame_range)
    if not match:
        raise ValueError("frame range %r: give FIRST-LAST or FIRST-LASTxSTEP" % frame_range)
    step = match.group(3)
    return "#FRAME_START#-#FRAME_END#" + ("x" + step if step and step != "1" else "")


def develop_command(darkroom, input_pattern, output_pattern, frame_range, look=None, extra_args=()):
    """The shell command one task runs: darkroom on its chunk, with the task's threads."""
    args = [darkroom, "develop", input_pattern, "-o", output_pattern,
            "--frames", chunk_frames_flag(frame_range), "--no-clobber", "-q"]
    if look:
        args += ["--look", look]
    args += list(extra_args)
    # The frame tokens are replaced before the shell runs, so they may start a word.
    script = " ".join(a if a.startswith("#FRAME") else _shell_word(a) for a in args)
    script += ' --threads "${CUE_THREADS:-0}"'
    return "/bin/sh -c " + shlex.quote(script)


def build_job(show, shot, input_pattern, output_pattern, frame_range, chunk, look=None,
              darkroom="darkroom", cores=None, user=None, extra_args=()):
    """The outline (OpenCue job) for a shot: one Shell layer over the frame range, in chunks."""
    job = outline.Outline("%s_darkroom" % shot, frame_range=frame_range, show=show, shot=shot,
                          user=user)
    layer_args = {"command": develop_command(darkroom, input_pattern, output_pattern, frame_range,
                                             look, extra_args),
                  "range": frame_range, "chunk": chunk}
    if cores:
        layer_args["cores"] = cores
    job.add_layer(Shell("develop", **layer_args))
    return job


def job_spec(job, user=None):
    """The XML job specification Cuebot receives, built offline."""
    launcher = outline.cuerun.OutlineLauncher(job, user=user)
    return launcher.serialize(use_pycuerun=False)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--show", required=True)
    parser.add_argument("--shot", required=True)
    parser.add_argument("--input", required=True, help="input sequence, e.g. plate.####.exr")
    parser.add_argument("--output", required=True, help="output sequence, e.g. film.####.exr")
    parser.add_argument("--frames", required=True, help="FIRST-LAST or FIRST-LASTxSTEP")
    parser.add_argument("--chunk", type=int, default=10, help="frames per task")
    parser.add_argument("--look", help="darkroom look file")
    parser.add_argument("--cores", type=float, help="cores to book per task (default: the service's)")
    parser.add_argument("--darkroom", default="darkroom", help="the darkroom program on the render nodes")
    parser.add_argument("--user")
    parser.add_argument("--launch", action="store_true", help="submit to Cuebot instead of printing the spec")
    a = parser.parse_args()
    job = build_job(a.show, a.shot, a.input, a.output, a.frames, a.chunk, a.look, a.darkroom,
                    a.cores, a.user)
    if a.launch:
        outline.cuerun.launch(job, use_pycuerun=False, user=a.user)
    else:
        print(job_spec(job, a.user))


if __name__ == "__main__":
    main()
