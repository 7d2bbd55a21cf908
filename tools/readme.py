"""Helpers of the README-writing scripts (tools/*.sh).

    python3 tools/readme.py replace SECTION FILE
        put FILE's contents between `<!-- BEGIN SECTION -->` and `<!-- END SECTION -->` in
        README.md

and, imported with PYTHONPATH=tools, `bench_rows`, `table` and `slope` for the tables of
`cargo qemu bench` runs (tools/bench-report.sh).
"""
import re
import sys

ORDERS = [1, 2, 4, 8, 16, 32]


def replace(name, path):
    body = open(path).read().rstrip("\n")
    readme = open("README.md").read()
    begin, end = f"<!-- BEGIN {name} -->", f"<!-- END {name} -->"
    if begin not in readme or end not in readme:
        sys.exit(f"README.md has no {begin} ... {end} section")
    pre, rest = readme.split(begin, 1)
    _, post = rest.split(end, 1)
    open("README.md", "w").write(f"{pre}{begin}\n{body}\n{end}{post}")
    print(f"README.md: section {name} updated")


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
    else:
        sys.exit(__doc__)
