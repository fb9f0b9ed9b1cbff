#!/usr/bin/env python3
"""One run against the fusion of several (`dala fuse`), over start frames: a table of
docs/results.md.

    python3 scripts/fused_runs_table.py --dala build/tools/dala --runs DIR --dataset DATA \\
        --label NAME [--runs DIR2 --dataset DATA2 --label NAME2 ...] [--fuse 1,3,5] \\
        [--write docs/results.md --marker MARKER]

Each DIR holds `dala run` output folders named S<start>_D<draw> (the run of DATA from
--first_frame <start> with --set ransac_order_seed=<draw>). For each N of --fuse the draws are
taken in disjoint groups of N (0..N-1, N..2N-1, ...; N = 1: each draw alone); each group's runs of
a start are fused by `dala fuse` (N > 1) and evaluated by `dala eval --json` against DATA's
poses.txt (with its times.txt), Sim(3)-aligned for one camera and SE(3) for a metric run, as
`dala run` evaluates. Per dataset and N: the groups, the median over groups of the starts'
median ATE, and the worst start's ATE (the median over groups, and the worst of all). With
--write, the table replaces the text between `<!-- MARKER:begin -->` and `<!-- MARKER:end -->`.
Standard library only.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import tempfile

from markdown_block import print_or_write


def evaluate(dala, data, trajectory, metric):
    out = subprocess.run(
        [dala, "eval", os.path.join(data, "poses.txt"), trajectory, "--times",
         os.path.join(data, "times.txt"), "--align", "se3" if metric else "sim3", "--json"],
        check=True, capture_output=True, text=True).stdout
    return json.loads(out)["ate"]["rmse"]


def is_metric(run_dir):
    with open(os.path.join(run_dir, "report.json")) as f:
        return json.load(f)["summary"]["scale_source"].startswith("metric")


def rows(dala, runs_dir, data, label, sizes, scratch):
    found = {}
    for name in os.listdir(runs_dir):
        m = re.fullmatch(r"S(\d+)_D(\d+)", name)
        if m and os.path.exists(os.path.join(runs_dir, name, "trajectory.txt")):
            found.setdefault(int(m.group(1)), set()).add(int(m.group(2)))
    starts = sorted(found)
    draws = sorted(set.intersection(*found.values()))
    metric = is_metric(os.path.join(runs_dir, "S%d_D%d" % (starts[0], draws[0])))
    out = []
    for n in sizes:
        groups = [draws[i:i + n] for i in range(0, len(draws) - n + 1, n)]
        medians, worsts = [], []
        for group in groups:
            ates = []
            for s in starts:
                folders = [os.path.join(runs_dir, "S%d_D%d" % (s, d)) for d in group]
                if n == 1:
                    trajectory = os.path.join(folders[0], "trajectory.txt")
                else:
                    fused = os.path.join(scratch, "S%d_%s" % (s, "_".join(map(str, group))))
                    subprocess.run([dala, "fuse", *folders, "--out", fused], check=True,
                                   capture_output=True)
                    trajectory = os.path.join(fused, "trajectory.txt")
                ates.append(evaluate(dala, data, trajectory, metric))
            medians.append(statistics.median(ates))
            worsts.append(max(ates))
        out.append("| %s | %s | %d | %d | %.4f | %.4f | %.4f |" % (
            label, "1 (one run)" if n == 1 else "%d fused" % n, len(starts), len(groups),
            statistics.median(medians), statistics.median(worsts), max(worsts)))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--dala", required=True)
    parser.add_argument("--runs", action="append", required=True)
    parser.add_argument("--dataset", action="append", required=True)
    parser.add_argument("--label", action="append", required=True)
    parser.add_argument("--fuse", default="1,3,5")
    parser.add_argument("--write")
    parser.add_argument("--marker", default="fused-runs")
    args = parser.parse_args()
    if not len(args.runs) == len(args.dataset) == len(args.label):
        parser.error("give one --dataset and one --label per --runs")
    sizes = [int(x) for x in args.fuse.split(",")]
    lines = ["| runs of | runs per trajectory | starts | draw groups | median ATE over starts (m) |"
             " worst start (m, median over groups) | worst start (m, worst group) |",
             "|---|---|---:|---:|---:|---:|---:|"]
    with tempfile.TemporaryDirectory() as scratch:
        for runs_dir, data, label in zip(args.runs, args.dataset, args.label):
            lines += rows(args.dala, runs_dir, data, label, sizes, scratch)
    print_or_write("\n".join(lines) + "\n", args.write, args.marker)


if __name__ == "__main__":
    main()
