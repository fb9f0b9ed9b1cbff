#!/usr/bin/env python3
"""The RANSAC-draws table of docs/results.md: KITTI 06 from ten start frames x nine draws.

    python3 scripts/draws_table.py DIR [--write docs/results.md [--marker NAME]]

DIR holds one file per configuration, MODE.CONFIG.txt (MODE mono or stereo; CONFIG "defaults"
or the --set assignment, e.g. mono.stereo.sigma_px=0.5.txt), with one line per run:
"START SEED ATE" (the --first_frame, the ransac_order_seed and the run's ATE RMSE in metres;
docs/results.md has the loop that writes them). Per configuration: the median, 90th percentile
and maximum over its runs, the share at or under 0.030 m, the median over the seeds of each
seed's ten-start median and worst, and the mean of log(ATE / the defaults' ATE) over the same
(start, seed) pairs with its standard error (in %). With --write, the table replaces the text
between `<!-- NAME:begin -->` and `<!-- NAME:end -->` of that file (NAME: --marker, default
draws). Standard library only.
"""
import argparse
import math
import os
import statistics

from markdown_block import print_or_write
from run_lines import read_runs


def load(path):
    return read_runs(path, int)


def row(mode, config, runs, base):
    values = sorted(runs.values())
    n = len(values)
    seeds = sorted({s for _, s in runs})
    per_seed = [[a for (f, s), a in runs.items() if s == seed] for seed in seeds]
    paired = ""
    if runs is not base:
        logs = [math.log(a / base[k]) for k, a in runs.items() if k in base]
        paired = "%+.1f %% (%.1f)" % (100 * statistics.mean(logs),
                                      100 * statistics.pstdev(logs) / math.sqrt(len(logs)))
    return "| %s | %s | %.4f | %.4f | %.4f | %d %% | %.4f | %.4f | %s |" % (
        mode, "defaults" if config == "defaults" else "`%s`" % config, statistics.median(values),
        values[max(0, math.ceil(0.9 * n) - 1)], values[-1],
        round(100 * sum(v <= 0.030 for v in values) / n),
        statistics.median(statistics.median(v) for v in per_seed),
        statistics.median(max(v) for v in per_seed), paired)


def table(directory):
    files = sorted(f for f in os.listdir(directory) if f.endswith(".txt"))
    lines = ["| mode | configuration | median | p90 | max | runs <= 0.030 m | 10-start median |"
             " 10-start worst | paired |", "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for mode in ("mono", "stereo"):
        base_file = os.path.join(directory, mode + ".defaults.txt")
        if not os.path.exists(base_file):
            continue
        base = load(base_file)
        lines.append(row(mode, "defaults", base, base))
        for f in files:
            if f.startswith(mode + ".") and f != mode + ".defaults.txt":
                lines.append(row(mode, f[len(mode) + 1:-4], load(os.path.join(directory, f)), base))
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("directory")
    parser.add_argument("--write", metavar="MARKDOWN")
    parser.add_argument("--marker", default="draws")
    args = parser.parse_args()
    text = table(args.directory)
    print_or_write(text, args.write, args.marker)


if __name__ == "__main__":
    main()
