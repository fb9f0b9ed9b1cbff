#!/usr/bin/env python3
"""The +-25 % sweep table of docs/results.md, made from a `dala bench` results.json.

    dala bench benchmarks/sweep_defaults.yaml --out sweep_out --jobs 2
    python3 scripts/sweep_table.py sweep_out/results.json [--write docs/results.md]

Configurations are named BASE or BASE.SETTING.m25 / BASE.SETTING.p25 (benchmarks/
sweep_defaults.yaml); each is compared with BASE (the defaults) on the same runs. Per
configuration and sequence, the median and the worst ATE over its runs (start frames or seeds);
the ratio to the defaults' median and worst. A row is flagged when a ratio leaves [1/1.5, 1.5]:
the +-25 % moved a median or a worst case by more than 1.5x. With --write, the table replaces
the text between the markers `<!-- sweep:begin -->` and `<!-- sweep:end -->` of that file.
Standard library only.
"""
import argparse
import json
import statistics
import sys

from markdown_block import print_or_write

LIMIT = 1.5


def group(results):
    """{config: {sequence: [ate or None per run]}} from results.json's runs."""
    out = {}
    for run in results["runs"]:
        ate = run.get("ate_rmse") if run.get("status") == "ok" else None
        out.setdefault(run["config"], {}).setdefault(run["sequence"], []).append(ate)
    return out


def stats(values):
    """(median, worst, failed) of a run list; a failed run counts as infinitely bad."""
    failed = sum(v is None for v in values)
    ok = [v for v in values if v is not None]
    if not ok:
        return None, None, failed
    worst = float("inf") if failed else max(ok)
    return statistics.median(ok), worst, failed


def ratio_text(value, base):
    if value is None or base is None or base <= 0:
        return "n/a", None
    if value == float("inf"):
        return "failed", float("inf")
    r = value / base
    return f"{r:.2f}x", r


def table(results):
    groups = group(results)
    sequences = sorted({s for per in groups.values() for s in per})
    lines = []
    header = "| configuration | " + " | ".join(
        f"{s} median / worst [m]" for s in sequences) + " | largest move |"
    lines.append(header)
    lines.append("|---|" + "---:|" * len(sequences) + "---|")
    flagged = []
    for config in sorted(groups, key=lambda c: (c.split(".")[0], c != c.split(".")[0], c)):
        base = groups.get(config.split(".")[0], {})
        cells = []
        largest = (1.0, "")
        for seq in sequences:
            values = groups[config].get(seq)
            if not values:
                cells.append("")
                continue
            med, worst, failed = stats(values)
            if med is None:
                cells.append(f"all {failed} failed")
                continue
            cell = f"{med:.4f} / {worst:.4f}" if worst != float("inf") else f"{med:.4f} / ({failed} failed)"
            if config != config.split(".")[0] and seq in base:
                bmed, bworst, _ = stats(base[seq])
                tm, rm = ratio_text(med, bmed)
                tw, rw = ratio_text(worst, bworst)
                cell += f" ({tm} / {tw})"
                for r, what in ((rm, "median"), (rw, "worst")):
                    if r is None:
                        continue
                    move = r if r >= 1 else 1 / r
                    if move > (largest[0] if largest[0] >= 1 else 1 / largest[0]):
                        largest = (r, f"{seq} {what}")
            cells.append(cell)
        if config == config.split(".")[0]:
            move_text = "(the defaults)"
        else:
            r = largest[0]
            move_text = f"{r:.2f}x {largest[1]}" if largest[1] else "1.00x"
            if r > LIMIT or r < 1 / LIMIT:
                move_text = f"**{move_text}**"
                flagged.append(config)
        lines.append(f"| {config} | " + " | ".join(cells) + f" | {move_text} |")
    lines.append("")
    lines.append(f"Rows moving a median or a worst case by more than {LIMIT}x: "
                 + (", ".join(flagged) if flagged else "none") + ".")
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("results", help="results.json of `dala bench benchmarks/sweep_defaults.yaml`")
    parser.add_argument("--write", help="a Markdown file whose sweep markers get the table")
    args = parser.parse_args()
    try:
        with open(args.results) as f:
            results = json.load(f)
    except (OSError, ValueError) as e:
        sys.exit(f"sweep_table: cannot read {args.results}: {e}")
    text = table(results)
    print_or_write(text, args.write, "sweep")


if __name__ == "__main__":
    main()
