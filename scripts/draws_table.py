#!/usr/bin/env python3
"""The RANSAC-draws table of docs/results.md: KITTI 06 from ten start frames x nine draws.

    python3 scripts/draws_table.py DIR [--write docs/results.md [--marker NAME]]

DIR holds one file per configuration, MODE.CONFIG.txt (MODE mono or stereo; CONFIG "defaults"
or the --set assignment, e.g. mono.stereo.sigma_px=0.5.txt), with one line per run:
"START SEED ATE [WITH_POSE FRAMES]" (the --first_frame, the ransac_order_seed, the run's ATE
RMSE in metres or "nan" when it has none, the frames with a pose and the frames run;
docs/results.md has the loop that writes them). Per configuration: the median, 90th percentile
and maximum over its runs with an ATE, the share at or under 0.030 m, the median over the seeds
of each seed's ten-start median and worst, the mean of log(ATE / the defaults' ATE) over the
same (start, seed) pairs with its standard error (in %), and, when the files say, the runs that
gave every frame a pose (an ATE over fewer frames is not comparable: a one-camera run that
starts its map late is evaluated on the frames after it). With --write, the table replaces the text
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
    return {k: a for k, a in read_runs(path, int).items() if not math.isnan(a)}


def posed_throughout(path):
    """'K of N' runs whose frames all have a pose, '-' when the file does not say."""
    runs = [line.split() for line in open(path) if line.strip()]
    if not runs or any(len(r) < 5 for r in runs):
        return "-"
    return "%d of %d" % (sum(r[2] != "nan" and r[3] == r[4] for r in runs), len(runs))


def row(mode, config, runs, base, posed):
    values = sorted(runs.values())
    n = len(values)
    seeds = sorted({s for _, s in runs})
    per_seed = [[a for (f, s), a in runs.items() if s == seed] for seed in seeds]
    paired = ""
    if runs is not base:
        logs = [math.log(a / base[k]) for k, a in runs.items() if k in base]
        paired = "%+.1f %% (%.1f)" % (100 * statistics.mean(logs),
                                      100 * statistics.pstdev(logs) / math.sqrt(len(logs)))
    return "| %s | %s | %.4f | %.4f | %.4f | %d %% | %.4f | %.4f | %s | %s |" % (
        mode, "defaults" if config == "defaults" else "`%s`" % config, statistics.median(values),
        values[max(0, math.ceil(0.9 * n) - 1)], values[-1],
        round(100 * sum(v <= 0.030 for v in values) / n),
        statistics.median(statistics.median(v) for v in per_seed),
        statistics.median(max(v) for v in per_seed), paired, posed)


def table(directory):
    files = sorted(f for f in os.listdir(directory) if f.endswith(".txt"))
    lines = ["| mode | configuration | median | p90 | max | runs <= 0.030 m | 10-start median |"
             " 10-start worst | paired | every frame posed |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for mode in ("mono", "stereo"):
        base_file = os.path.join(directory, mode + ".defaults.txt")
        if not os.path.exists(base_file):
            continue
        base = load(base_file)
        lines.append(row(mode, "defaults", base, base, posed_throughout(base_file)))
        for f in files:
            if f.startswith(mode + ".") and f != mode + ".defaults.txt":
                path = os.path.join(directory, f)
                lines.append(row(mode, f[len(mode) + 1:-4], load(path), base,
                                 posed_throughout(path)))
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
