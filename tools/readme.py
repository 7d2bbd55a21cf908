"""Helpers of the scripts that write the measured blocks of README.md and the guides
(tools/*.sh).

A block is the text between `<!-- BEGIN name -->` and `<!-- END name -->` in one of the pages,
README.md and docs/*.md; each name is in exactly one page.

    python3 tools/readme.py replace SECTION FILE
        put FILE's contents into the block SECTION of the page that holds it
    python3 tools/readme.py check SECTION FILE
        exit 1 with a diff when the block SECTION differs from FILE's contents
    python3 tools/readme.py markers
        exit 1 naming the fault unless every BEGIN has its END in the same page, every name is
        in one page only, every block a tool writes (`replace NAME` in tools/*.sh) exists, and
        every block is written by a tool

and, imported with PYTHONPATH=tools, `split` (a block's page, as before, block, after), and
`bench_rows`, `table` and `slope` for the tables of `cargo qemu bench` runs
(tools/bench-report.sh).
"""
import difflib
import glob
import os
import re
import sys

ORDERS = [1, 2, 4, 8, 16, 32]
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MARKER = re.compile(r"<!-- (BEGIN|END) (\S+) -->")
# `replace NAME` in a tool's shell code (not in a comment); NAME is literal.
WRITES = re.compile(r"(?:^|[;&|({]|\bthen|\bdo|\belse)\s*replace\s+\"?([A-Za-z0-9][\w.-]*)\"?(?=\s)")


def pages():
    """The pages that may hold blocks, relative to the repository: README.md, docs/*.md."""
    found = ["README.md"] + sorted(os.path.relpath(p, ROOT)
                                   for p in glob.glob(os.path.join(ROOT, "docs", "*.md")))
    return [p for p in found if os.path.isfile(os.path.join(ROOT, p))]


def read(page):
    with open(os.path.join(ROOT, page)) as f:
        return f.read()


def locate(name):
    """The page that holds the block `name`; exits when none or more than one does."""
    begin = f"<!-- BEGIN {name} -->"
    holders = [p for p in pages() if begin in read(p)]
    if not holders:
        sys.exit(f"no page ({', '.join(pages())}) has a {begin} ... <!-- END {name} --> block")
    if len(holders) > 1:
        sys.exit(f"{begin} is in more than one page: {', '.join(holders)}")
    return holders[0]


def split(name):
    """The page holding the block `name` as (before, block, after) around its markers."""
    page = locate(name)
    text = read(page)
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    pre, rest = text.split(begin, 1)
    if end not in rest:
        sys.exit(f"{page}: {begin} has no {end} after it")
    body, post = rest.split(end, 1)
    return f"{pre}{begin}\n", body.strip("\n"), f"\n{end}{post}"


def replace(name, path):
    page = locate(name)
    pre, _, post = split(name)
    with open(path) as f:
        new = f.read().rstrip("\n")
    with open(os.path.join(ROOT, page), "w") as f:
        f.write(pre + new + post)
    print(f"{page}: section {name} updated")


def check(name, path):
    page = locate(name)
    with open(path) as f:
        want = f.read().rstrip("\n")
    have = split(name)[1]
    if want != have:
        diff = difflib.unified_diff(have.splitlines(), want.splitlines(), page, path,
                                    lineterm="")
        sys.exit(f"{page}: section {name} is stale:\n" + "\n".join(diff))
    print(f"{page}: section {name} is current")


def written():
    """{name: [tool, ..]} of the blocks the tools write (`replace NAME` in tools/*.sh)."""
    names = {}
    for tool in sorted(glob.glob(os.path.join(ROOT, "tools", "*.sh"))):
        with open(tool) as f:
            for line in f:
                if line.lstrip().startswith("#"):
                    continue
                for name in WRITES.findall(line):
                    names.setdefault(name, [])
                    rel = os.path.relpath(tool, ROOT)
                    if rel not in names[name]:
                        names[name].append(rel)
    return names


def markers():
    """Exits 1 listing every fault of the blocks' markers; prints the blocks when none."""
    faults, where = [], {}
    for page in pages():
        open_name, open_line = None, 0
        for number, line in enumerate(read(page).splitlines(), 1):
            for kind, name in MARKER.findall(line):
                if kind == "BEGIN":
                    if open_name:
                        faults.append(f"{page}:{number}: BEGIN {name} inside the block "
                                      f"{open_name} (line {open_line})")
                    open_name, open_line = name, number
                    where.setdefault(name, []).append(f"{page}:{number}")
                elif open_name != name:
                    faults.append(f"{page}:{number}: END {name} without its BEGIN"
                                  + (f" (block {open_name} open since line {open_line})"
                                     if open_name else ""))
                else:
                    open_name = None
        if open_name:
            faults.append(f"{page}:{open_line}: BEGIN {open_name} has no END")
    for name, places in where.items():
        if len(places) > 1:
            faults.append(f"block {name} is in more than one place: {', '.join(places)}")
    tools = written()
    for name, by in sorted(tools.items()):
        if name not in where:
            faults.append(f"{', '.join(by)} writes block {name}, which no page has")
    for name, places in where.items():
        if name not in tools:
            faults.append(f"{places[0]}: block {name} is written by no tool (tools/*.sh)")
    if faults:
        sys.exit(f"markers: {len(faults)} fault{'s' if len(faults) > 1 else ''}:\n  "
                 + "\n  ".join(faults))
    order = {page: i for i, page in enumerate(pages())}
    at = {name: (places[0].rsplit(":", 1)[0], int(places[0].rsplit(":", 1)[1]))
          for name, places in where.items()}
    for name, (page, line) in sorted(at.items(), key=lambda kv: (order[kv[1][0]], kv[1][1])):
        print(f"{page}:{line}: {name} ({', '.join(tools[name])})")
    print(f"markers: {len(where)} blocks in {len({page for page, _ in at.values()})} pages, each "
          "in one page, each BEGIN with its END, each written by a tool")


def bench_rows(text, key="insns/sample"):
    """{(estimator, scalar): {p: n}} of the bench lines with `key=`."""
    rows = {}
    pattern = r"(\w+) (\w+) p=(\d+) " + re.escape(key) + r"=(\d+)"
    for est, scalar, p, n in re.findall(pattern, text):
        rows.setdefault((est, scalar), {})[int(p)] = int(n)
    return rows


def table(rows, orders=ORDERS):
    """A markdown table, one row per (estimator, scalar), one column per order."""
    lines = ["| estimator | scalar | " + " | ".join(f"p = {p}" for p in orders) + " |",
             "|---|---|" + "---|" * len(orders)]
    for (est, scalar), r in rows.items():
        lines.append(f"| {est} | {scalar} | " + " | ".join(str(r.get(p, "")) for p in orders) + " |")
    return "\n".join(lines) + "\n"


def slope(r, orders=ORDERS):
    """Least-squares slope of r[p] over the orders: the cost of one lattice stage."""
    ps = [p for p in orders if p in r]
    mp, my = sum(ps) / len(ps), sum(r[p] for p in ps) / len(ps)
    return sum((p - mp) * (r[p] - my) for p in ps) / sum((p - mp) ** 2 for p in ps)


if __name__ == "__main__":
    if sys.argv[1:2] == ["replace"] and len(sys.argv) == 4:
        replace(sys.argv[2], sys.argv[3])
    elif sys.argv[1:2] == ["check"] and len(sys.argv) == 4:
        check(sys.argv[2], sys.argv[3])
    elif sys.argv[1:] == ["markers"]:
        markers()
    else:
        sys.exit(__doc__)
