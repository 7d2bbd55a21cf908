"""Helpers of the README-writing scripts (tools/*.sh).

    python3 tools/readme.py replace SECTION FILE
        put FILE's contents between `<!-- BEGIN SECTION -->` and `<!-- END SECTION -->` in
        README.md
    python3 tools/readme.py check SECTION FILE
        exit 1 with a diff when that section of README.md differs from FILE's contents

and, imported with PYTHONPATH=tools, `bench_rows`, `table` and `slope` for the tables of
`cargo qemu bench` runs (tools/bench-report.sh).
"""
import difflib
import re
import sys

ORDERS = [1, 2, 4, 8, 16, 32]


def split(name):
    """README.md as (before, section, after) around the section's markers."""
    readme = open("README.md").read()
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    if begin not in readme or end not in readme:
        sys.exit(f"README.md has no {begin} ... {end} section")
    pre, rest = readme.split(begin, 1)
    body, post = rest.split(end, 1)
    return f"{pre}{begin}\n", body.strip("\n"), f"\n{end}{post}"


def replace(name, path):
    pre, _, post = split(name)
    open("README.md", "w").write(pre + open(path).read().rstrip("\n") + post)
    print(f"README.md: section {name} updated")


def check(name, path):
    want, have = open(path).read().rstrip("\n"), split(name)[1]
    if want != have:
        diff = difflib.unified_diff(have.splitlines(), want.splitlines(), "README.md", path,
                                    lineterm="")
        sys.exit(f"README.md: section {name} is stale:\n" + "\n".join(diff))
    print(f"README.md: section {name} is current")


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
    else:
        sys.exit(__doc__)
