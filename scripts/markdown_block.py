"""Rewrites the generated block of a markdown file: the text between `<!-- NAME:begin -->` and
`<!-- NAME:end -->` (the tables that scripts write from runs into docs/results.md and
docs/benchmarks.md)."""
import os
import sys


def write_block(path, name, text):
    """Replaces the block NAME of the file at path with text (which should end with a newline),
    atomically: a temporary file beside it, then renamed over it, so an interrupted write leaves
    the old file. Exits naming the file if it has no such markers."""
    begin, end = "<!-- %s:begin -->\n" % name, "<!-- %s:end -->" % name
    with open(path) as f:
        doc = f.read()
    if begin not in doc or end not in doc:
        script = os.path.splitext(os.path.basename(sys.argv[0]))[0]
        sys.exit("%s: %s has no %s ... %s markers" % (script, path, begin.strip(), end))
    head, rest = doc.split(begin, 1)
    tail = rest.split(end, 1)[1]
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        f.write(head + begin + text + end + tail)
    os.replace(tmp, path)


def print_or_write(text, path, name):
    """The table scripts' output: text on stdout without a path (--write not given), else the
    block NAME of the file at path replaced with it (write_block)."""
    if path:
        write_block(path, name, text)
    else:
        sys.stdout.write(text)
