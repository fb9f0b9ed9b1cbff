#!/usr/bin/env python3
"""Paired runs of two configurations, per preset: the table of ATE ratios in docs/results.md.

    python3 scripts/paired_runs_table.py MODE:BASE:NEW [MODE:BASE:NEW ...] \\
        [--write docs/results.md --marker rendered-sigma]

BASE and NEW are files with one line per run, "NAME DRAW ATE": NAME the sequence folder
(PRESET_SEED, e.g. rover_loop_2), DRAW the ransac_order_seed, ATE the run's ATE RMSE in metres.
Runs are paired on (NAME, DRAW). Per preset and over all: the number of pairs, the geometric
means of both ATEs, their ratio NEW / BASE with the standard error of the mean log ratio, and the
pairs more than 1.5x worse / better. With --write, the table replaces the text between
`<!-- MARKER:begin -->` and `<!-- MARKER:end -->` of that file. Standard library only.
"""
import argparse
import math
import statistics
import sys

from markdown_block import print_or_write
from run_lines import read_runs


def load(path):
    return read_runs(path, str)


def row(mode, preset, base, new, keys):
    logs = [math.log(new[k] / base[k]) for k in keys]
    se = statistics.stdev(logs) / math.sqrt(len(logs)) if len(logs) > 1 else float("nan")
    geomean = lambda runs: math.exp(statistics.mean(math.log(runs[k]) for k in keys))
    return "| %s | %s | %d | %.4f | %.4f | %.3f (%.3f) | %d | %d |" % (
        mode, preset, len(keys), geomean(base), geomean(new), math.exp(statistics.mean(logs)), se,
        sum(l > math.log(1.5) for l in logs), sum(l < -math.log(1.5) for l in logs))


def table(specs):
    lines = ["| mode | preset | runs | base geomean (m) | new geomean (m) | ratio (se of log) |"
             " > 1.5x worse | > 1.5x better |", "|---|---|---:|---:|---:|---:|---:|---:|"]
    for spec in specs:
        mode, base_path, new_path = spec.split(":")
        base, new = load(base_path), load(new_path)
        keys = sorted(k for k in new if k in base)
        if not keys:
            sys.exit("%s and %s share no (name, draw) pair" % (base_path, new_path))
        presets = sorted({name.rsplit("_", 1)[0] for name, _ in keys})
        for preset in presets:
            lines.append(row(mode, preset, base, new,
                             [k for k in keys if k[0].rsplit("_", 1)[0] == preset]))
        lines.append(row(mode, "**all**", base, new, keys))
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("specs", nargs="+", metavar="MODE:BASE:NEW")
    parser.add_argument("--write", metavar="MARKDOWN")
    parser.add_argument("--marker", default="rendered-sigma")
    args = parser.parse_args()
    text = table(args.specs)
    print_or_write(text, args.write, args.marker)


if __name__ == "__main__":
    main()
