#!/usr/bin/env python3
"""Runs with several draws (`dala run --draws N`) from a `dala bench` folder: each draw alone
against their fusion, per sequence: the table of docs/results.md.

    python3 scripts/draws_runs_table.py BENCH_DIR --config NAME \\
        [--write docs/results.md --marker MARKER]

BENCH_DIR is a `dala bench --out` folder whose configuration NAME has `draws: N`: each of its
runs' report.json gives every draw's ATE (summary.draws.per_draw) and the fused trajectory's
(summary.ate). Per sequence (the runs of its seeds or start frames) and over all: the runs; the
median and worst ATE of draw 0 (the run without --draws), of every draw alone (all draws of all
runs) and of the fused trajectories; the geometric mean of fused / the run's median draw and of
fused / draw 0, with the standard error of the mean log ratio; and how often draw 0 was the
best of its run's draws (by chance: one run in N). Runs without an evaluation, or whose draws
were not all fused, are left out and counted; a run without a report.json is not seen. With --write, the table replaces the text between `<!-- MARKER:begin -->` and
`<!-- MARKER:end -->` of that file. Standard library only.
"""
import argparse
import glob
import json
import math
import os
import statistics

from markdown_block import print_or_write


def load(bench_dir, config):
    """sequence -> list of (per-draw ATEs, fused ATE); and the runs left out per sequence."""
    runs, left_out = {}, {}
    pattern = os.path.join(bench_dir, "runs", "*", config, "report.json")
    for path in sorted(glob.glob(pattern)):
        sequence = os.path.basename(os.path.dirname(os.path.dirname(path))).split("@")[0]
        with open(path) as f:
            summary = json.load(f)["summary"]
        draws = summary.get("draws")
        if draws is None:
            raise SystemExit("%s: no summary.draws: was %s run with --draws N > 1?" % (path, config))
        ates = [d["ate_rmse"] for d in draws["per_draw"]]
        # Left out: no evaluation, or the draws were not all fused (summary.ate is then one
        # draw's, not a fusion of them all).
        if "ate" not in summary or any(a is None for a in ates) or draws["fused"] != len(ates):
            left_out[sequence] = left_out.get(sequence, 0) + 1
            continue
        runs.setdefault(sequence, []).append((ates, summary["ate"]["rmse"]))
    return runs, left_out


def mean_se(logs):
    if not logs:
        return "-"
    se = statistics.stdev(logs) / math.sqrt(len(logs)) if len(logs) > 1 else float("nan")
    return "%.3f (%.3f)" % (math.exp(statistics.mean(logs)), se)


def row(name, runs, left_out):
    if not runs:
        return "| %s | 0 (%d left out) | | | | | | |" % (name, left_out)
    draw0 = [d[0] for d, _ in runs]
    every = [a for d, _ in runs for a in d]
    fused = [f for _, f in runs]
    n = len(runs[0][0])
    vs_median = [math.log(f / statistics.median(d)) for d, f in runs]
    vs_draw0 = [math.log(f / d[0]) for d, f in runs]
    best0 = sum(d[0] == min(d) for d, _ in runs)
    count = "%d" % len(runs) + (" (%d left out)" % left_out if left_out else "")
    return "| %s | %s | %.4f / %.4f | %.4f / %.4f | %.4f / %.4f | %s | %s | %d of %d (chance: 1 in %d) |" % (
        name, count, statistics.median(draw0), max(draw0), statistics.median(every), max(every),
        statistics.median(fused), max(fused), mean_se(vs_median), mean_se(vs_draw0), best0,
        len(runs), n)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("bench_dir")
    parser.add_argument("--config", required=True)
    parser.add_argument("--write")
    parser.add_argument("--marker")
    args = parser.parse_args()
    runs, left_out = load(args.bench_dir, args.config)
    if not runs and not left_out:
        raise SystemExit("no run of configuration %s under %s/runs" % (args.config, args.bench_dir))
    lines = ["| sequence | runs | draw 0: median / worst ATE (m) | each draw alone: median / worst "
             "| fused: median / worst | fused / the run's median draw (se of log) | fused / draw 0 "
             "(se of log) | draw 0 the best draw |",
             "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name in sorted(set(runs) | set(left_out)):
        lines.append(row(name, runs.get(name, []), left_out.get(name, 0)))
    everything = [r for name in sorted(runs) for r in runs[name]]
    lines.append(row("all", everything, sum(left_out.values())))
    print_or_write("\n".join(lines), args.write, args.marker)


if __name__ == "__main__":
    main()
