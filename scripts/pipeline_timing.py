#!/usr/bin/env python3
"""The whole-pipeline timing table of docs/benchmarks.md, made from `dala run`s on this machine.

    python3 scripts/pipeline_timing.py [--dala build/tools/dala] [--repeats 3]
                                       [--write docs/benchmarks.md]

Runs `dala run` (defaults, --progress=false) in stereo and with one camera (--mode mono) on the
KITTI 06 clip of ../shared/data (left out with a message when absent) and on the rendered
rover_loop (`dala synth --preset rover_loop --frames 300 --seed 1`, written to a temporary
folder). Each run is repeated; per row the median over the repeats of report.json's
summary.ms_median (per frame, wall), of the stage medians (summary.stages_ms: detect, stereo,
track_motion, reacquire, estimator) and of the slowest frame. Run it on an otherwise idle
machine: the numbers are wall times. With --write, the table replaces the text between the markers
`<!-- timing:begin -->` and `<!-- timing:end -->` of that file. Standard library only.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

from markdown_block import write_block

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KITTI = os.path.join(ROOT, "..", "shared", "data", "kitti06_0000-0050")


def quiet(cmd):
    """Runs cmd; on failure prints what it said and exits."""
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        sys.exit("pipeline_timing: {} failed ({}):\n{}".format(" ".join(cmd), done.returncode,
                                                                done.stdout))


def run(dala, seq, mode, out):
    """report.json's summary of one `dala run`."""
    cmd = [dala, "run", seq, "--out", out, "--progress=false"]
    if mode == "mono":
        cmd += ["--mode", "mono"]
    quiet(cmd)
    with open(os.path.join(out, "report.json")) as f:
        return json.load(f)["summary"]


def row(name, summaries):
    """One table row: medians over the repeats."""
    def med(get):
        return statistics.median(get(s) for s in summaries)
    stage = lambda key: med(lambda s: s["stages_ms"].get(key, {}).get("median", 0.0))
    s0 = summaries[0]
    return "| {} | {} | {} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.1f} | {:.0f} |".format(
        name, s0["frames"], s0["keyframes"], med(lambda s: s["ms_median"]), stage("detect"),
        stage("stereo"), stage("track_motion"), stage("reacquire"), stage("estimator"),
        med(lambda s: s["ms_max"]))


def table(dala, repeats, workdir):
    sequences = []
    if os.path.isdir(KITTI):
        sequences.append(("KITTI 06 0-50, 1226x370", KITTI))
    else:
        print("pipeline_timing: {} is absent; KITTI rows left out".format(KITTI), file=sys.stderr)
    rover = os.path.join(workdir, "rover_loop")
    quiet([dala, "synth", "--preset", "rover_loop", "--frames", "300", "--seed", "1", "--out",
           rover])
    sequences.append(("rendered rover_loop 300, 752x480", rover))
    lines = ["| run | frames | keyframes | ms per frame (median) | detect | stereo | "
             "track + motion | reacquire | estimator | slowest frame [ms] |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, seq in sequences:
        for mode in ("stereo", "mono"):
            out = os.path.join(workdir, "run")
            summaries = [run(dala, seq, mode, out) for _ in range(repeats)]
            lines.append(row("{}, {}".format(name, mode), summaries))
    return "\n".join(lines)


def write(path, text):
    write_block(path, "timing", text + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--dala", default=os.path.join(ROOT, "build", "tools", "dala"))
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--write", help="the markdown file whose timing table to replace")
    args = parser.parse_args()
    if not os.access(args.dala, os.X_OK):
        sys.exit("pipeline_timing: no dala binary at {} (make build, or --dala PATH)".format(
            args.dala))
    with tempfile.TemporaryDirectory(prefix="dala_timing_") as workdir:
        text = table(args.dala, args.repeats, workdir)
    print(text)
    if args.write:
        write(args.write, text)


if __name__ == "__main__":
    main()
