"""Rewrites the generated block of a markdown file: the text between `<!-- NAME:begin -->` and
`<!-- NAME:end -->` (the tables of docs/results.md that scripts write from runs)."""
import sys


def write_block(path, name, text):
    """Replaces the block NAME of the file at path with text; exits naming the file if the file
    has no such markers."""
    begin, end = "<!-- %s:begin -->\n" % name, "<!-- %s:end -->" % name
    with open(path) as f:
        doc = f.read()
    if begin not in doc or end not in doc:
        sys.exit("%s has no %s ... %s markers" % (path, begin.strip(), end))
    head, rest = doc.split(begin, 1)
    tail = rest.split(end, 1)[1]
    with open(path, "w") as f:
        f.write(head + begin + text + end + tail)
