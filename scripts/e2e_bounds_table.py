#!/usr/bin/env python3
"""docs/reliability.md's table of end-to-end bounds, from the tests' own output.

Each bound is checked by testing::ExpectWithinBound (tests/test_util.h), which prints
    [ bound ] Suite.Test | quantity | measured | best | bound | unit
This script reads those lines from test logs (ctest's Testing/Temporary/LastTest.log, or a
gtest binary's output) and
  --write DOC   rewrites the table between <!-- e2e-bounds:begin --> and <!-- e2e-bounds:end -->
                (rows of tests absent from the logs, e.g. skipped without the shared data, are
                kept as they were);
  --check DOC   exits 1 when a bound in the logs is not the one the table shows, or the table
                lacks it (CI runs this after the test suite: the table cannot drift from the
                tests).

  python3 scripts/e2e_bounds_table.py --write docs/reliability.md build/Testing/Temporary/LastTest.log
"""
import argparse
import os
import re
import sys

BEGIN = "<!-- e2e-bounds:begin -->"
END = "<!-- e2e-bounds:end -->"
HEADER = ("| test | quantity | measured | best recorded | bound (1.5x best) | bound / measured |\n"
          "|---|---|---:|---:|---:|---:|\n")
LINE = re.compile(r"\[ bound \] (\S+) \| (.*?) \| (\S+) \| (\S+) \| (\S+) \| (.*)$")


def read_bounds(paths):
    """(test, quantity) -> dict(measured, best, bound, unit), in the order first seen."""
    bounds = {}
    for path in paths:
        with open(path, errors="replace") as f:
            for line in f:
                m = LINE.search(line.rstrip("\n"))
                if m:
                    test, quantity, measured, best, bound, unit = m.groups()
                    bounds[(test, quantity)] = dict(measured=float(measured), best=float(best),
                                                    bound=float(bound), unit=unit.strip())
    return bounds


def fmt(value, unit):
    return "%.4g %s" % (value, unit)


def row(test, quantity, b):
    ratio = b["bound"] / b["measured"] if b["measured"] > 0 else float("inf")
    return "| `%s` | %s | %s | %s | %s | %.2f |\n" % (
        test, quantity, fmt(b["measured"], b["unit"]), fmt(b["best"], b["unit"]),
        fmt(b["bound"], b["unit"]), ratio)


def split_doc(text, path):
    a, b = text.find(BEGIN), text.find(END)
    if a < 0 or b < a:
        sys.exit("%s: no %s ... %s markers" % (path, BEGIN, END))
    return text[:a + len(BEGIN)], text[a + len(BEGIN):b], text[b:]


def table_rows(table):
    """(test, quantity) -> (row text, bound text) from the current table."""
    rows = {}
    for line in table.splitlines(keepends=True):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 6 and cells[0].startswith("`"):
            rows[(cells[0].strip("`"), cells[1])] = (line, cells[4])
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", metavar="DOC")
    mode.add_argument("--check", metavar="DOC")
    parser.add_argument("logs", nargs="+")
    args = parser.parse_args()
    bounds = read_bounds(args.logs)
    if not bounds:
        sys.exit("no '[ bound ]' lines in %s: run the tests first" % ", ".join(args.logs))
    doc = args.write or args.check
    with open(doc) as f:
        text = f.read()
    head, table, tail = split_doc(text, doc)
    old = table_rows(table)
    if args.check:
        wrong = []
        for (test, quantity), b in bounds.items():
            shown = old.get((test, quantity))
            expected = fmt(b["bound"], b["unit"])
            if shown is None:
                wrong.append("%s: '%s' is not in the table" % (test, quantity))
            elif shown[1] != expected:
                wrong.append("%s: '%s': the test's bound is %s, the table says %s"
                             % (test, quantity, expected, shown[1]))
        if wrong:
            print("%s is out of date with the tests (regenerate: %s --write %s LOG):\n  %s"
                  % (doc, sys.argv[0], doc, "\n  ".join(wrong)), file=sys.stderr)
            return 1
        print("[e2e-bounds] %d bounds in the logs match %s" % (len(bounds), doc))
        return 0
    rows = dict((key, line) for key, (line, _) in old.items())
    for (test, quantity), b in bounds.items():
        rows[(test, quantity)] = row(test, quantity, b)
    body = "\n" + HEADER + "".join(rows[k] for k in sorted(rows)) + "\n"
    with open(doc + ".tmp", "w") as f:
        f.write(head + body + tail)
    os.replace(doc + ".tmp", doc)
    print("[e2e-bounds] %d rows written to %s (%d from the logs)" % (len(rows), doc, len(bounds)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
